#pragma once
/// The processes of a run started by mpirun, the partition of the tets among them, and the
/// reductions that keep the state every rank holds identical.

#include <map>
#include <memory>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// The ranks of PETSc's world communicator (PETSc and MPI start on construction). Every rank
/// holds the whole state (all node positions) and evaluates the energy of its own tets; the
/// sums below make energies, gradients and step bounds the same on every rank, so that every
/// rank takes the same Newton path. With one rank there is nothing to construct: the serial
/// code path is the one without a Ranks.
class Ranks {
 public:
  /// How many processes mpirun started together (Open MPI's OMPI_COMM_WORLD_SIZE), 1 outside
  /// mpirun; read from the environment, without starting MPI.
  static int launched();
  /// This process's rank among them (OMPI_COMM_WORLD_RANK), 0 outside mpirun.
  static int launched_rank();
  /// Whether a Ranks of several processes has been constructed in this process.
  static bool running();
  /// Ends every process of the run at once (MPI_Abort) with exit code `code`, where one rank
  /// fails alone and the others would wait for it forever.
  [[noreturn]] static void abort_run(int code);

  Ranks();
  ~Ranks();
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  /// Splits the tets (#tets x 4, all of them, the same on every rank) among the ranks with
  /// PETSc's graph partitioner (MatPartitioning, PT-Scotch unless -mat_partitioning_type says
  /// otherwise) on their dual graph (tets sharing a face), run by rank 0 alone and broadcast.
  /// Each node then belongs to the lowest rank among its tets'.
  void partition(const TetIndices& tets, Index num_nodes);
  /// The rank of each tet / node (after partition()).
  const std::vector<int>& tet_owner() const { return tet_owner_; }
  const std::vector<int>& node_owner() const { return node_owner_; }
  /// Whether this rank owns tet t.
  bool owns_tet(Index t) const { return tet_owner_[static_cast<size_t>(t)] == rank_; }

  /// The sum over ranks of `value`, on every rank (+infinity where some rank has it).
  double sum(double value) const;
  /// The smallest over ranks of `value`, on every rank.
  double min(double value) const;
  /// Every rank's `v` (the same length on all) summed entry by entry, into `v` on every rank:
  /// the non-zero entries go into a PETSc vector (ADD_VALUES; those of rows another rank owns
  /// travel in PETSc's stash) that is then scattered to all (VecScatterCreateToAll).
  void sum(VectorX& v);
  /// Every rank's `mine` (of any length) one after another, rank 0's first, on every rank: a
  /// PETSc vector with `mine` as this rank's part, scattered to all (VecScatterCreateToAll).
  std::vector<double> concatenate(const std::vector<double>& mine) const;

 private:
  struct Vectors;  // the PETSc vectors and scatter of sum(VectorX&) for one length
  int rank_ = 0, size_ = 1;
  std::vector<int> tet_owner_, node_owner_;
  std::map<Index, std::unique_ptr<Vectors>> vectors_;  // by length
};

}  // namespace depthfem
