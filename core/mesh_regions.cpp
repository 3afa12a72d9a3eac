#include "core/mesh_regions.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "core/overlap_check.hpp"

namespace depthfem {

namespace {
std::string list(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "'" : ", '") + n + "'";
  return out.empty() ? "none" : out;
}
}  // namespace

LoadedMesh select_regions(const LoadedMesh& mesh, const std::vector<std::string>& regions) {
  // Position in `regions` of each region of the mesh, or -1.
  std::vector<Index> position(mesh.region_names.size(), -1);
  for (size_t k = 0; k < regions.size(); ++k) {
    const auto it = std::ranges::find(mesh.region_names, regions[k]);
    if (it == mesh.region_names.end()) {
      throw InputError("no region '" + regions[k] + "' (the mesh has " + list(mesh.region_names) +
                       ")");
    }
    Index& p = position[it - mesh.region_names.begin()];
    if (p >= 0) throw InputError("region '" + regions[k] + "' is selected twice");
    p = static_cast<Index>(k);
  }
  LoadedMesh out;
  out.region_names = regions;
  const Index num_nodes = static_cast<Index>(mesh.mesh.X.rows());
  std::vector<Index> new_index(static_cast<size_t>(num_nodes), -1);
  std::vector<Index> kept_tets;
  for (Index t = 0; t < mesh.mesh.tets.rows(); ++t) {
    if (position[mesh.tet_region[t]] < 0) continue;
    kept_tets.push_back(t);
    for (int c = 0; c < 4; ++c) new_index[mesh.mesh.tets(t, c)] = 0;
  }
  Index next = 0;
  std::vector<Index> kept_nodes;
  for (Index i = 0; i < num_nodes; ++i) {
    if (new_index[i] == 0) {
      new_index[i] = next++;
      kept_nodes.push_back(i);
    }
  }
  out.mesh.X.resize(next, 3);
  for (Index i = 0; i < num_nodes; ++i)
    if (new_index[i] >= 0) out.mesh.X.row(new_index[i]) = mesh.mesh.X.row(i);
  out.mesh.tets.resize(static_cast<Index>(kept_tets.size()), 4);
  for (size_t k = 0; k < kept_tets.size(); ++k) {
    const Index t = kept_tets[k];
    for (int c = 0; c < 4; ++c) out.mesh.tets(k, c) = new_index[mesh.mesh.tets(t, c)];
    out.tet_region.push_back(position[mesh.tet_region[t]]);
  }
  if (mesh.neighbours.rows() == mesh.mesh.tets.rows()) {
    // A neighbour left out makes the face part of the boundary.
    std::vector<Index> new_tet(static_cast<size_t>(mesh.mesh.tets.rows()), -1);
    for (size_t k = 0; k < kept_tets.size(); ++k) new_tet[kept_tets[k]] = static_cast<Index>(k);
    out.neighbours.resize(out.mesh.tets.rows(), 4);
    for (size_t k = 0; k < kept_tets.size(); ++k) {
      for (int c = 0; c < 4; ++c) {
        const Index across = mesh.neighbours(kept_tets[k], c);
        out.neighbours(k, c) = across < 0 ? -1 : new_tet[across];
      }
    }
  }
  for (const auto& [name, nodes] : mesh.node_sets) {
    std::vector<Index> kept;
    for (Index i : nodes)
      if (new_index[i] >= 0) kept.push_back(new_index[i]);
    if (!kept.empty()) out.node_sets[name] = std::move(kept);
  }
  out.source = mesh.source.subset(kept_tets, kept_nodes);
  check_no_overlap(out.mesh, out.source, out.neighbours);
  return out;
}

}  // namespace depthfem
