#pragma once
/// Reader for TetGen NAME.node + NAME.ele mesh pairs.

#include <string>

#include "core/mesh_file.hpp"

namespace depthfem {

/// Reads NAME.node and NAME.ele, given "NAME", "NAME.node" or "NAME.ele". '#' starts a comment;
/// point attributes, boundary markers and region attributes are read past and dropped. Numbering
/// starts at 0 or 1, as the first point decides. Throws InputError naming file, line and node or
/// tetrahedron for malformed numbers, truncated files, undefined node references and 10-node
/// (quadratic) tetrahedra; the mesh is then checked by validate_and_orient and check_no_overlap
/// (one body), whose messages name points and tetrahedra by their numbers in the files.
LoadedMesh read_tetgen(const std::string& path);

}  // namespace depthfem
