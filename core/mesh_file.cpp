#include "core/mesh_file.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "core/gmsh_reader.hpp"
#include "core/tetgen_reader.hpp"
#include "core/text_parsing.hpp"

namespace depthfem {

LoadedMesh read_tet_mesh(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".msh") return read_gmsh(path);
  if (ext == ".node" || ext == ".ele") return read_tetgen(path);
  if (ext == ".obj") {
    throw InputError(located(path, 0,
                             "an OBJ file holds a triangle surface, not a tetrahedral mesh; "
                             "tetrahedralize it first (TetGen or Gmsh) and give the .node/.ele or "
                             ".msh file"));
  }
  throw InputError(located(path, 0,
                           "unknown mesh file extension '" + ext +
                               "' (expected .msh for Gmsh, .node or .ele for TetGen)"));
}

LoadedMesh finish_loaded_mesh(const std::vector<double>& xyz, const std::vector<Index>& tets,
                              const MeshSource& source) {
  if (tets.empty()) throw InputError(located(source.file, 0, "contains no 4-node tetrahedra"));
  LoadedMesh out;
  out.mesh.X = from_row_major<Points>(xyz);
  out.mesh.tets = from_row_major<TetIndices>(tets);
  out.reoriented = validate_and_orient(out.mesh, source, &out.neighbours);
  out.source = source;
  return out;
}

}  // namespace depthfem
