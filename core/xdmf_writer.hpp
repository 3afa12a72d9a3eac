#pragma once
/// The XDMF sidecar of a results file: the XML through which ParaView reads the HDF5 datasets
/// as a time series of multiblock data sets (one tetrahedral block per body, or per element
/// region of a body with several, plus the boundary surface), written step by step at a cost
/// per step that does not grow with the run, and complete whenever the run is killed.

#include <ios>
#include <string>
#include <vector>

#include "core/exclusive_file.hpp"
#include "core/results_file.hpp"
#include "core/types.hpp"

namespace depthfem {

/// One tetrahedral block of the sidecar: a body, or an element region of a body (with the body's
/// nodes): a contiguous range of the scene's nodes and one of its tets.
struct SidecarBlock {
  std::string name;  ///< the block's name in ParaView
  /// Dataset of its tets with block-local node indices: "/mesh/tets" for a block that is the
  /// whole mesh, else "/mesh/blocks/<k>/tets".
  std::string tets;
  Index num_nodes = 0, num_tets = 0;
  Index first_node = 0, first_tet = 0;  ///< its first rows in the scene's node and tet datasets
};

/// How a sidecar names a part of a dataset (a step's row of a /steps dataset, a block's rows):
/// ParaView's Xdmf3 readers and its older XDMF Reader each read only their own notation.
enum class XdmfDialect {
  kXdmf3,  ///< "FILE:DATASET|start:stride:count:dimensions" (Xdmf3 Reader S and T)
  kXdmf2,  ///< a DataItem of ItemType HyperSlab (XDMF Reader)
};

/// What the sidecar lists from a results file.
struct SidecarLayout {
  std::string h5_name;  ///< the results file, as the sidecar names it (relative to the sidecar)
  XdmfDialect dialect = XdmfDialect::kXdmf3;
  Index num_nodes = 0, num_tets = 0, num_tris = 0;
  std::vector<SidecarBlock> blocks;
  bool depth = false;  ///< /mesh/depth exists
  ResultFields fields;
};

/// A named per-step value (1 or 3 components), shown by ParaView as field data.
struct StepValue {
  std::string name;
  std::vector<double> values;
};

/// One state the sidecar lists.
struct SidecarStep {
  Index row = -1;   ///< its row in the /steps datasets; -1: the reference state (/reference)
  double time = 0;  ///< load factor (static) or time [s]
  std::vector<StepValue> values;
};

/// Writes the sidecar of a results file: a temporal collection whose every state is a spatial
/// collection of one tetrahedral grid per block and the grid "boundary" (the boundary triangles,
/// which carry the contact fields and the step's values).
///
/// The sidecar is complete at every instant, even when the run is killed in the middle of a
/// write or the disk fills: two copies of it exist, the file at `path` and a hidden spare beside
/// it (".NAME.xmf.XXXXXXXX", created exclusively). A step is written in place of the spare's
/// closing tags (which follow it again), the two names are then exchanged in one atomic rename,
/// and the step is written into the other copy, now the spare. The cost of a step is that of
/// writing it twice, whatever the number of steps before. On a file system without exchanging
/// renames the spare replaces the sidecar and a new spare is copied from it (a cost that grows
/// with the run). The spare is removed with the writer; a killed run leaves it behind.
class XdmfSidecar {
 public:
  /// Writes `path` (a new file renamed to it) and its spare with the `reference` state as their
  /// first entry. Throws InputError naming `path` when they cannot be written.
  XdmfSidecar(std::string path, SidecarLayout layout, const SidecarStep& reference);
  XdmfSidecar(XdmfSidecar&&) noexcept = default;
  XdmfSidecar& operator=(XdmfSidecar&&) noexcept = default;
  XdmfSidecar(const XdmfSidecar&) = delete;
  XdmfSidecar& operator=(const XdmfSidecar&) = delete;
  /// Removes the spare.
  ~XdmfSidecar();

  /// Appends a state. Throws InputError naming the sidecar when it cannot be written; the
  /// sidecar then still lists every state appended before.
  void append(const SidecarStep& step);

 private:
  /// The XML of one state.
  std::string state(const SidecarStep& step) const;
  [[noreturn]] void fail(const std::string& what) const;

  std::string path_;
  SidecarLayout layout_;
  FileDescriptor live_;   ///< the copy named `path_`
  FileDescriptor spare_;  ///< the copy named `spare_path_`
  std::string spare_path_;
  std::streamoff end_ = 0;  ///< offset of the closing tags, the same in both copies
  bool broken_ = false;     ///< a write failed: the spare no longer equals the sidecar
};

}  // namespace depthfem
