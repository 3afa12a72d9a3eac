#pragma once
// A Gmsh file with two element regions, shared by the reader and scene-file tests.

namespace depthfem::testing {

// MSH 2.2 (the first element tag is the physical group): five nodes with arbitrary tags at
// 1.5 x (the unit tet's corners and (1, 1, 1)) + (0.1, -0.2, 0.3); two positively oriented tets
// sharing the face (7, 300, 12), element 3 in the physical volume "soft" (tag 1) and element 4 in
// "bone" (tag 2); the triangle (50, 7, 300) in the surface "base plate" and node 9 in the unnamed
// point group 7. Tets on lines 22 and 23.
inline constexpr const char* kTwoRegionMsh = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
3
2 5 "base plate"
3 1 "soft"
3 2 "bone"
$EndPhysicalNames
$Nodes
5
50 0.1 -0.2 0.3
7 1.6 -0.2 0.3
300 0.1 1.3 0.3
12 0.1 -0.2 1.8
9 1.6 1.3 1.8
$EndNodes
$Elements
4
1 15 2 7 1 9
2 2 2 5 1 50 7 300
3 4 2 1 1 50 7 300 12
4 4 2 2 2 7 300 12 9
$EndElements
)";

}  // namespace depthfem::testing
