#include "core/mesh.hpp"

#include <stdexcept>

#include "core/boundary.hpp"

namespace depthfem {

namespace {
template <class M>
void append_rows(M& dst, const M& src) {
  const Eigen::Index old = dst.rows();
  dst.conservativeResize(old + src.rows(), Eigen::NoChange);
  dst.bottomRows(src.rows()) = src;
}
}  // namespace

Index Mesh::add_body(const std::string& name, const TetMesh& body, const NodeSets& sets,
                     const std::vector<std::string>& region_names,
                     const std::vector<Index>& tet_region) {
  Body b;
  b.name = name;
  b.first_node = num_nodes();
  b.num_nodes = static_cast<Index>(body.X.rows());
  b.first_tet = num_tets();
  b.num_tets = static_cast<Index>(body.tets.rows());
  b.first_tri = num_tris();

  // Regions in the order of their first tets; then each tet goes to the next row of its region
  // (a counting sort, stable).
  const Index num_regions = static_cast<Index>(region_names.size());
  if (!tet_region.empty() && static_cast<Index>(tet_region.size()) != b.num_tets)
    throw std::invalid_argument("body '" + name + "': " + std::to_string(tet_region.size()) +
                                " tet regions for " + std::to_string(b.num_tets) + " tets");
  std::vector<Index> order, count(static_cast<size_t>(num_regions), 0);
  for (const Index r : tet_region) {
    if (r < 0 || r >= num_regions)
      throw std::invalid_argument("body '" + name + "': tet region " + std::to_string(r) +
                                  " is not one of its " + std::to_string(num_regions) + " regions");
    if (count[r]++ == 0) order.push_back(r);
  }
  TetIndices grouped = body.tets;
  std::vector<Index> next_row(static_cast<size_t>(num_regions), 0);
  Index first = 0;
  for (const Index r : order) {
    b.regions.push_back({region_names[r], b.first_tet + first, count[r]});
    next_row[r] = first;
    first += count[r];
  }
  for (Index t = 0; t < static_cast<Index>(tet_region.size()); ++t)
    grouped.row(next_row[tet_region[t]]++) = body.tets.row(t);

  const BoundaryFaces faces = boundary_faces(grouped);
  b.num_tris = static_cast<Index>(faces.tris.rows());
  const Index id = static_cast<Index>(bodies.size());

  append_rows(X, body.X);
  append_rows(tets, TetIndices(grouped.array() + b.first_node));
  append_rows(tris, TriIndices(faces.tris.array() + b.first_node));
  append_rows(tri_tet, IndexVector(faces.tet.array() + b.first_tet));
  append_rows(tet_body, IndexVector(IndexVector::Constant(b.num_tets, id)));
  append_rows(tri_body, IndexVector(IndexVector::Constant(b.num_tris, id)));
  bodies.push_back(b);
  // Bodies follow each other, so appending keeps every set sorted.
  for (const auto& [set, nodes] : sets)
    for (Index i : nodes) node_sets[set].push_back(b.first_node + i);
  return id;
}

Mesh single_body_mesh(const TetMesh& body, const std::string& name) {
  Mesh m;
  m.add_body(name, body);
  return m;
}

}  // namespace depthfem
