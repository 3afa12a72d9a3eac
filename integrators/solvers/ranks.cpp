#include "integrators/solvers/ranks.hpp"

#include <petscmat.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <limits>

#include "integrators/solvers/petsc_session.hpp"

namespace depthfem {

namespace {

int environment_int(const char* name, int otherwise) {
  const char* text = std::getenv(name);
  return text ? std::atoi(text) : otherwise;
}

bool g_running = false;

// For each tet, the tets sharing a face with it (sorted), as compressed rows.
struct DualRows {
  std::vector<PetscInt> begin, neighbours;
};
DualRows dual_rows(const TetIndices& tets) {
  // Every face as its sorted node triple with its tet; equal triples are neighbouring tets.
  struct Face {
    std::array<Index, 3> nodes;
    Index tet;
  };
  std::vector<Face> faces;
  faces.reserve(static_cast<size_t>(4 * tets.rows()));
  for (Index t = 0; t < tets.rows(); ++t) {
    for (int k = 0; k < 4; ++k) {
      Face f{{}, t};
      for (int a = 0, j = 0; a < 4; ++a)
        if (a != k) f.nodes[j++] = tets(t, a);
      std::ranges::sort(f.nodes);
      faces.push_back(f);
    }
  }
  std::ranges::sort(faces, {}, [](const Face& f) { return std::pair(f.nodes, f.tet); });
  std::vector<std::vector<PetscInt>> adjacent(static_cast<size_t>(tets.rows()));
  for (size_t i = 0; i + 1 < faces.size(); ++i) {
    if (faces[i].nodes != faces[i + 1].nodes) continue;
    const Index a = faces[i].tet, b = faces[i + 1].tet;
    adjacent[static_cast<size_t>(a)].push_back(b);
    adjacent[static_cast<size_t>(b)].push_back(a);
  }
  DualRows out;
  out.begin.push_back(0);
  for (std::vector<PetscInt>& row : adjacent) {
    std::ranges::sort(row);
    out.neighbours.insert(out.neighbours.end(), row.begin(), row.end());
    out.begin.push_back(static_cast<PetscInt>(out.neighbours.size()));
  }
  return out;
}

}  // namespace

struct Ranks::Vectors {
  Vec parallel = nullptr, all = nullptr;
  VecScatter to_all = nullptr;
  ~Vectors() {
    VecScatterDestroy(&to_all);
    VecDestroy(&all);
    VecDestroy(&parallel);
  }
};

int Ranks::launched() {
  return std::max(1, environment_int("OMPI_COMM_WORLD_SIZE", 1));
}

int Ranks::launched_rank() {
  return environment_int("OMPI_COMM_WORLD_RANK", 0);
}

bool Ranks::running() {
  return g_running;
}

void Ranks::abort_run(int code) {
  MPI_Abort(PETSC_COMM_WORLD, code);
  std::abort();
}

Ranks::Ranks() {
  start_petsc();
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank_);
  MPI_Comm_size(PETSC_COMM_WORLD, &size_);
  g_running = size_ > 1;
}

Ranks::~Ranks() = default;

void Ranks::partition(const TetIndices& tets, Index num_nodes) {
  const Index n = tets.rows();
  tet_owner_.assign(static_cast<size_t>(n), 0);
  node_owner_.assign(static_cast<size_t>(num_nodes), 0);
  if (size_ == 1) return;
  // Every rank holds the whole mesh, so rank 0 partitions the whole dual graph on its own (a
  // one-process communicator asked for size_ parts) and sends the owners to the others. PT-Scotch
  // run on all ranks took longer than the rest of the run on a 16-core machine (14 s for 4,488
  // tets on 16 ranks, 17 s for 245,760 tets on 4; bench/results/distributed.md).
  if (rank_ == 0) {
    const DualRows rows = dual_rows(tets);
    PetscInt *begin = nullptr, *neighbours = nullptr;  // the adjacency matrix frees them
    petsc_check(PetscMalloc1(rows.begin.size(), &begin), "PetscMalloc1");
    petsc_check(PetscMalloc1(std::max<size_t>(rows.neighbours.size(), 1), &neighbours),
                "PetscMalloc1");
    std::ranges::copy(rows.begin, begin);
    std::ranges::copy(rows.neighbours, neighbours);
    Mat adjacency = nullptr;
    petsc_check(MatCreateMPIAdj(PETSC_COMM_SELF, n, n, begin, neighbours, nullptr, &adjacency),
                "MatCreateMPIAdj");
    MatPartitioning partitioner = nullptr;
    IS owners = nullptr;
    petsc_check(MatPartitioningCreate(PETSC_COMM_SELF, &partitioner), "MatPartitioningCreate");
    petsc_check(MatPartitioningSetAdjacency(partitioner, adjacency), "MatPartitioningSetAdjacency");
    petsc_check(MatPartitioningSetNParts(partitioner, size_), "MatPartitioningSetNParts");
    petsc_check(MatPartitioningSetType(partitioner, MATPARTITIONINGPTSCOTCH),
                "MatPartitioningSetType");
    petsc_check(MatPartitioningSetFromOptions(partitioner), "MatPartitioningSetFromOptions");
    petsc_check(MatPartitioningApply(partitioner, &owners), "MatPartitioningApply");
    const PetscInt* owner = nullptr;
    petsc_check(ISGetIndices(owners, &owner), "ISGetIndices");
    for (Index t = 0; t < n; ++t) tet_owner_[static_cast<size_t>(t)] = static_cast<int>(owner[t]);
    ISRestoreIndices(owners, &owner);
    ISDestroy(&owners);
    MatPartitioningDestroy(&partitioner);
    MatDestroy(&adjacency);
  }
  MPI_Bcast(tet_owner_.data(), static_cast<int>(n), MPI_INT, 0, PETSC_COMM_WORLD);
  std::ranges::fill(node_owner_, size_);
  for (Index t = 0; t < n; ++t)
    for (int a = 0; a < 4; ++a) {
      int& o = node_owner_[static_cast<size_t>(tets(t, a))];
      o = std::min(o, tet_owner_[static_cast<size_t>(t)]);
    }
  for (int& o : node_owner_) o = o == size_ ? 0 : o;  // a node of no tet (none after validation)
}

double Ranks::sum(double value) const {
  double out = 0;
  MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD);
  return out;
}

double Ranks::min(double value) const {
  double out = 0;
  MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MIN, PETSC_COMM_WORLD);
  return out;
}

void Ranks::sum(VectorX& v) {
  if (size_ == 1) return;
  std::unique_ptr<Vectors>& kept = vectors_[v.size()];
  if (!kept) {
    kept = std::make_unique<Vectors>();
    petsc_check(VecCreateMPI(PETSC_COMM_WORLD, PETSC_DECIDE, v.size(), &kept->parallel),
                "VecCreateMPI");
    petsc_check(VecScatterCreateToAll(kept->parallel, &kept->to_all, &kept->all),
                "VecScatterCreateToAll");
  }
  Vectors& s = *kept;
  std::vector<PetscInt> rows;
  std::vector<PetscScalar> values;
  for (Index i = 0; i < v.size(); ++i)
    if (v(i) != 0) {
      rows.push_back(i);
      values.push_back(v(i));
    }
  petsc_check(VecSet(s.parallel, 0.0), "VecSet");
  petsc_check(VecSetValues(s.parallel, static_cast<PetscInt>(rows.size()), rows.data(),
                           values.data(), ADD_VALUES),
              "VecSetValues");
  petsc_check(VecAssemblyBegin(s.parallel), "VecAssemblyBegin");
  petsc_check(VecAssemblyEnd(s.parallel), "VecAssemblyEnd");
  petsc_check(VecScatterBegin(s.to_all, s.parallel, s.all, INSERT_VALUES, SCATTER_FORWARD),
              "VecScatterBegin");
  petsc_check(VecScatterEnd(s.to_all, s.parallel, s.all, INSERT_VALUES, SCATTER_FORWARD),
              "VecScatterEnd");
  const PetscScalar* all = nullptr;
  petsc_check(VecGetArrayRead(s.all, &all), "VecGetArrayRead");
  std::copy(all, all + v.size(), v.data());
  VecRestoreArrayRead(s.all, &all);
}

std::vector<double> Ranks::concatenate(const std::vector<double>& mine) const {
  Vec part = nullptr, all = nullptr;
  VecScatter to_all = nullptr;
  petsc_check(VecCreateMPIWithArray(PETSC_COMM_WORLD, 1, static_cast<PetscInt>(mine.size()),
                                    PETSC_DECIDE, mine.data(), &part),
              "VecCreateMPIWithArray");
  petsc_check(VecScatterCreateToAll(part, &to_all, &all), "VecScatterCreateToAll");
  petsc_check(VecScatterBegin(to_all, part, all, INSERT_VALUES, SCATTER_FORWARD),
              "VecScatterBegin");
  petsc_check(VecScatterEnd(to_all, part, all, INSERT_VALUES, SCATTER_FORWARD), "VecScatterEnd");
  PetscInt length = 0;
  petsc_check(VecGetSize(all, &length), "VecGetSize");
  const PetscScalar* values = nullptr;
  petsc_check(VecGetArrayRead(all, &values), "VecGetArrayRead");
  std::vector<double> out(values, values + length);
  VecRestoreArrayRead(all, &values);
  VecScatterDestroy(&to_all);
  VecDestroy(&all);
  VecDestroy(&part);
  return out;
}

}  // namespace depthfem
