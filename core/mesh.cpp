#include "core/mesh.hpp"

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

Index Mesh::add_body(const std::string& name, const TetMesh& body, const NodeSets& sets) {
  Body b;
  b.name = name;
  b.first_node = num_nodes();
  b.num_nodes = static_cast<Index>(body.X.rows());
  b.first_tet = num_tets();
  b.num_tets = static_cast<Index>(body.tets.rows());
  b.first_tri = num_tris();
  const BoundaryFaces faces = boundary_faces(body.tets);
  b.num_tris = static_cast<Index>(faces.tris.rows());
  const Index id = static_cast<Index>(bodies.size());

  append_rows(X, body.X);
  append_rows(tets, TetIndices(body.tets.array() + b.first_node));
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
