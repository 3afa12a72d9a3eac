#pragma once
/// Whether the tets of one body overlap: a mesh that is not a tetrahedralisation of its volume.

#include "core/tet_mesh.hpp"

namespace depthfem {

/// Throws InputError when tets of `mesh`, one body that validate_and_orient accepted (every tet
/// positively oriented, every face in one tet or in two on opposite sides), overlap. The message is
/// located at the line of an element of the overlap and names the elements and nodes in the file's
/// numbering (`source`), e.g. "m.msh:30: element 49 (line 30) overlaps element 12 (line 23): ...".
///
/// With every tet positive and interior faces cancelling, the number of tets covering a point p
/// equals the winding number w(p) of the body's boundary triangles, so the tets overlap exactly
/// where w >= 2. The check therefore
///  1. tests every pair of boundary triangles (bounding-volume tree) and rejects a pair that
///     crosses (each one's interior passes through the other's), two that lie in one plane and
///     overlap with both tets on the same side, and a vertex or edge that touches the interior
///     of another triangle from the inner side; pairs sharing a vertex or an edge included;
///  2. links the sides of the boundary triangles that face the same space: the inner sides of two
///     triangles at an edge of two, and around an edge of more (bodies touching along an edge)
///     the sides facing each wedge between neighbours in angle; w on the inner side of a triangle
///     is w on its outer side + 1;
///  3. evaluates w exactly once per connected group of linked triangles: the generalized winding
///     number (the sum of the solid angles of the triangles, Van Oosterom and Strackee) at the
///     centroid of one of its triangles, seen from inside; closed groups whose bounding box does
///     not hold that point add nothing and are skipped. Every triangle must have w = 1 on its
///     inner side and 0 on its outer side (a cavity included; a tet floating inside another gives
///     2 inside and 1 outside).
///
/// Guarantee, in exact arithmetic: step 1 rejects only true overlaps of positive volume (each of
/// its cases puts interior points of both tets together). When the boundary triangles meet only in
/// the vertices and edges they share, or not at all, steps 2 and 3 give every side of every
/// triangle the true w of the space it faces (w is constant on each region the boundary encloses,
/// and every region is bounded by some side), so the mesh is rejected if and only if tets overlap.
/// Boundaries that touch without crossing are accepted where that is how two parts of a valid body
/// can touch (coincident faces with tets on opposite sides, a vertex or an edge touching from
/// outside) and rejected where it implies overlap (touching from inside); with such contacts the
/// "if and only if" is not proven (the randomised tests, unions of grid cells with nodes shared or
/// doubled and extra tets on grid nodes, find no wrong answer). In floating point, a sign within
/// 1e-10 of the triangles' size (or of the rounding of their coordinates) counts as zero, so an
/// overlap thinner than that may pass; a centroid that falls on another triangle's edge gives a w
/// off an integer, and the group's next triangles are tried.
/// Cost: about linear in the number of boundary triangles (the tree's pairs are those whose boxes
/// meet), plus, per group of step 3 (a surface component), the triangles of the groups whose boxes
/// hold its evaluation point; quadratic only when many separate surfaces lie in one's box. On the
/// fine knee mesh (161 k tets, 26 k boundary triangles over its three bodies) it is a few percent
/// of loading the scene.
/// `neighbours`: the tets across the faces as validate_and_orient gives them (#tets x 4, -1 on
/// the boundary), which spares finding the boundary again; empty: found here.
void check_no_overlap(const TetMesh& mesh, const MeshSource& source = {},
                      const TetIndices& neighbours = {});

}  // namespace depthfem
