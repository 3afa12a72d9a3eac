#pragma once
/// The XDMF sidecar of a results file: the XML that lets ParaView read the HDF5 datasets as a
/// temporal collection of tetrahedral grids.

#include <string>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// A written step, as the sidecar lists it.
struct SidecarStep {
  std::string name;   ///< grid name ("000012")
  std::string group;  ///< HDF5 group holding the step's datasets ("/steps/000012")
  double load = 0;    ///< written as the grid's time
  bool has_velocity = false;
};

/// XDMF 3 text of a temporal collection with one tetrahedral grid per step (Time = load), its
/// positions, node depth, cell body and node velocity (when written) taken from `h5_name`.
std::string xdmf_text(const std::string& h5_name, Index num_nodes, Index num_tets,
                      const std::vector<SidecarStep>& steps);

/// Replaces `path` by `text` through a temporary file and a rename, so that it is never partial.
/// Throws InputError naming `path` when it cannot be written.
void write_file_atomically(const std::string& path, const std::string& text);

}  // namespace depthfem
