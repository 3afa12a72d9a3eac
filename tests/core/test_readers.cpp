#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iomanip>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/gmsh_reader.hpp"
#include "core/mesh_edits.hpp"
#include "core/mesh_file.hpp"
#include "core/mesh_regions.hpp"
#include "core/obj_reader.hpp"
#include "core/tetgen_reader.hpp"
#include "core/two_region_msh.hpp"

namespace depthfem {
namespace {

namespace fs = std::filesystem;

// The reference mesh of every format: 5 nodes, 2 positively oriented tets sharing face (1,2,3).
// The coordinates are 1.5 * (unit tet corners and (1,1,1)) + (0.1, -0.2, 0.3), written so that they
// are not exactly representable: the readers must give the same doubles as the compiler.
Points reference_X() {
  Points X(5, 3);
  X << 0.1, -0.2, 0.3,  //
      1.6, -0.2, 0.3,   //
      0.1, 1.3, 0.3,    //
      0.1, -0.2, 1.8,   //
      1.6, 1.3, 1.8;
  return X;
}
TetIndices reference_tets() {
  TetIndices tets(2, 4);
  tets << 0, 1, 2, 3,  //
      1, 2, 3, 4;
  return tets;
}
// A point in the plane x + y + z = 1.7 of nodes 1, 2, 3: node 4 there makes tet 1 flat.
constexpr const char* kFlatNode4 = "0.6 0.4 0.7";

// MSH 2.2 with arbitrary node tags, a $PhysicalNames section, and a point, a line and a triangle
// before the two tets (lines 21 and 22).
constexpr const char* kMsh22 = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
1
3 1 "body"
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
5
1 15 2 0 1 50
2 1 2 0 1 50 7
3 2 2 0 1 50 7 300
4 4 2 1 1 50 7 300 12
5 4 2 1 1 7 300 12 9
$EndElements
)";

// MSH 4.1: $Entities skipped, three node blocks (the second parametric on a surface: x y z u v),
// a point, a triangle and a tet block (tets on lines 32 and 33), then a $NodeData section.
constexpr const char* kMsh41 = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$Entities
1 0 0 1
1 0.1 -0.2 0.3 0
1 0.1 -0.2 0.3 1.6 1.3 1.8 0 0
$EndEntities
$Nodes
3 5 7 300
0 1 0 1
50
0.1 -0.2 0.3
2 1 1 1
7
1.6 -0.2 0.3 0.5 0.25
3 1 0 3
300
12
9
0.1 1.3 0.3
0.1 -0.2 1.8
1.6 1.3 1.8
$EndNodes
$Elements
3 4 1 4
0 1 15 1
1 50
2 1 2 1
2 50 7 300
3 1 4 2
3 50 7 300 12
4 7 300 12 9
$EndElements
$NodeData
1
"temperature"
$EndNodeData
)";

// MSH 4.1 with physical groups: tet 1 in volume "soft" (tag 1), tet 2 in volume "bone" (tag 2,
// listed negated as Gmsh does for a reversed orientation), the triangle (50, 7, 300) in the
// surface "base plate" and node 9 in the unnamed point group 7. Entities on lines 12 to 15.
constexpr const char* kMsh41Groups = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
2 5 "base plate"
3 1 "soft"
3 2 "bone"
$EndPhysicalNames
$Entities
1 0 1 2
1 1.6 1.3 1.8 1 7
1 0 0 0 2 2 2 1 5 0
1 0 0 0 2 2 2 1 1 0
2 0 0 0 2 2 2 1 -2 0
$EndEntities
$Nodes
1 5 1 300
3 1 0 5
50
7
300
12
9
0.1 -0.2 0.3
1.6 -0.2 0.3
0.1 1.3 0.3
0.1 -0.2 1.8
1.6 1.3 1.8
$EndNodes
$Elements
4 4 1 4
0 1 15 1
1 9
2 1 2 1
2 50 7 300
3 1 4 1
3 50 7 300 12
3 2 4 1
4 7 300 12 9
$EndElements
)";

// TetGen pair numbered from 0, with comments, a blank line, one attribute and boundary markers.
constexpr const char* kTetgenNode0 = R"(# five points, one attribute, boundary markers
5 3 1 1
0 0.1 -0.2 0.3 7.5 1
1 1.6 -0.2 0.3 7.5 1

2 0.1 1.3 0.3 7.5 0  # comment after a point
3 0.1 -0.2 1.8 7.5 1
4 1.6 1.3 1.8 7.5 0
)";
constexpr const char* kTetgenEle0 = R"(2 4 1
0 0 1 2 3 1.0
1 1 2 3 4 1.0
)";
// The same pair numbered from 1, without attributes or markers.
constexpr const char* kTetgenNode1 = R"(5 3 0 0
1 0.1 -0.2 0.3
2 1.6 -0.2 0.3
3 0.1 1.3 0.3
4 0.1 -0.2 1.8
5 1.6 1.3 1.8
)";
constexpr const char* kTetgenEle1 = R"(# tets
2 4 0
1 1 2 3 4
2 2 3 4 5
)";

// OBJ with a quad, every slash form, a w coordinate, negative indices and ignored statements.
// A closed pyramid, every face oriented outward: the square base (line 13, normal -z) and four
// sides (lines 15, 16, 18, 19).
constexpr const char* kObj = R"(# square and pyramid
mtllib a.mtl
o thing
v 0 0 0
v 1 0 0
v 1 1 0 1.0
v 0 1 0
vt 0 0
vn 0 0 1
g grp
s off
usemtl m
f 1/1/1 4/1/1 3/1/1 2/1/1
v 0.5 0.5 1
f -5//1 -4//1 -1//1
f 2/1 3/1 5/1
l 1 2
f 3 4 5  # side
f 4 1 5  # last face
)";

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

// `text` with its line `n` (1-based) replaced by `replacement`.
std::string replace_line(const std::string& text, size_t n, const std::string& replacement) {
  std::vector<std::string> lines = split_lines(text);
  lines.at(n - 1) = replacement;
  return join_lines(lines);
}

// The first `n` lines of `text`.
std::string first_lines(const std::string& text, size_t n) {
  std::vector<std::string> lines = split_lines(text);
  lines.resize(n);
  return join_lines(lines);
}

// Success when `read` throws an InputError whose message contains every one of `parts`.
template <class Read>
::testing::AssertionResult throws_input_error(const Read& read,
                                              std::initializer_list<std::string_view> parts) {
  try {
    read();
  } catch (const InputError& e) {
    const std::string message = e.what();
    for (const std::string_view part : parts) {
      if (message.find(part) == std::string::npos) {
        return ::testing::AssertionFailure()
               << "message \"" << message << "\" does not contain \"" << part << "\"";
      }
    }
    return ::testing::AssertionSuccess() << message;
  }
  return ::testing::AssertionFailure() << "no InputError thrown";
}

void expect_reference_mesh(const LoadedMesh& loaded) {
  EXPECT_TRUE(loaded.mesh.X == reference_X()) << loaded.mesh.X;
  EXPECT_TRUE(loaded.mesh.tets == reference_tets()) << loaded.mesh.tets;
  EXPECT_EQ(loaded.reoriented, 0);
}

void expect_positive_volumes(const TetMesh& mesh) {
  for (Index t = 0; t < mesh.tets.rows(); ++t) {
    EXPECT_GT(signed_volume(mesh.X.row(mesh.tets(t, 0)), mesh.X.row(mesh.tets(t, 1)),
                            mesh.X.row(mesh.tets(t, 2)), mesh.X.row(mesh.tets(t, 3))),
              0.0)
        << "tet " << t;
  }
}

// Gives each test its own temporary directory, removed afterwards.
class ReadersTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("depthfem_test_readers_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes `text` to `name` in the test directory and returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// ---- Gmsh ------------------------------------------------------------------------------------

TEST_F(ReadersTest, Gmsh22ReadsTetsAndSkipsLowerDimensionalElements) {
  expect_reference_mesh(read_gmsh(write("mesh.msh", kMsh22)));
}

TEST_F(ReadersTest, Gmsh41ReadsTetsAndSkipsLowerDimensionalElements) {
  expect_reference_mesh(read_gmsh(write("mesh.msh", kMsh41)));
}

TEST_F(ReadersTest, GmshToleratesCrlfLineEnds) {
  std::string crlf;
  for (const std::string& line : split_lines(kMsh22)) crlf += line + "\r\n";
  expect_reference_mesh(read_gmsh(write("mesh.msh", crlf)));
}

TEST_F(ReadersTest, GmshReorientsNegativeTetsAndCountsThem) {
  // Element 4 listed as (0, 2, 1, 3): negative; expected back as (0, 2, 3, 1).
  const LoadedMesh loaded =
      read_gmsh(write("flipped.msh", replace_line(kMsh22, 21, "4 4 2 1 1 50 300 7 12")));
  EXPECT_EQ(loaded.reoriented, 1);
  expect_positive_volumes(loaded.mesh);
  TetIndices expected = reference_tets();
  expected.row(0) << 0, 2, 3, 1;
  EXPECT_TRUE(loaded.mesh.tets == expected) << loaded.mesh.tets;
}

TEST_F(ReadersTest, GmshTruncatedInsideElementsIsAnError) {
  const std::string file = write("cut.msh", first_lines(kMsh22, 21));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"cut.msh:21:", "file ends inside $Elements", "expected 5 elements, read 4"}));
}

TEST_F(ReadersTest, GmshSectionEndingBeforeItsCountIsAnError) {
  const std::string file = write("short.msh", replace_line(kMsh22, 22, "$EndElements"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); }, {"short.msh:22:", "$Elements ends early",
                                                            "expected 5 elements, read 4"}));
}

TEST_F(ReadersTest, GmshMissingEndLineIsAnError) {
  const std::string file = write("noend.msh", first_lines(kMsh22, 22));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); }, {"noend.msh:22:", "file ends inside $Elements (no $EndElements)"}));
}

TEST_F(ReadersTest, GmshTruncatedInsideSkippedSectionIsAnError) {
  const std::string file = write("cut.msh", first_lines(kMsh41, 37));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"cut.msh:37:", "file ends inside $NodeData (started at line 35, no $EndNodeData)"}));
}

TEST_F(ReadersTest, GmshTruncatedInsidePhysicalNamesIsAnError) {
  const std::string file = write("cut.msh", first_lines(kMsh22, 6));
  EXPECT_TRUE(
      throws_input_error([&] { read_gmsh(file); },
                         {"cut.msh:6:", "file ends inside $PhysicalNames (no $EndPhysicalNames)"}));
}

TEST_F(ReadersTest, Gmsh41TruncatedInsideNodesIsAnError) {
  const std::string file = write("cut41.msh", first_lines(kMsh41, 20));
  EXPECT_TRUE(
      throws_input_error([&] { read_gmsh(file); },
                         {"cut41.msh:20:", "file ends inside $Nodes", "expected 5 nodes, read 2"}));
}

TEST_F(ReadersTest, Gmsh41BlocksShortOfTheAnnouncedCountIsAnError) {
  const std::string file = write("count41.msh", replace_line(kMsh41, 26, "3 5 1 5"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"count41.msh:33:", "the element blocks hold 4 elements but $Elements announced 5"}));
}

TEST_F(ReadersTest, GmshUndefinedNodeTagIsAnError) {
  const std::string file = write("undef.msh", replace_line(kMsh22, 22, "5 4 2 1 1 7 300 12 99"));
  EXPECT_TRUE(
      throws_input_error([&] { read_gmsh(file); },
                         {"undef.msh:22:", "element 5 references node 99, which is not defined"}));
}

TEST_F(ReadersTest, Gmsh41UndefinedNodeTagIsAnError) {
  const std::string file = write("undef41.msh", replace_line(kMsh41, 32, "3 50 7 301 12"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"undef41.msh:32:", "element 3 references node 301, which is not defined"}));
}

TEST_F(ReadersTest, GmshDuplicateNodeTagIsAnError) {
  const std::string file = write("dup.msh", replace_line(kMsh22, 13, "7 0.1 -0.2 1.8"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"dup.msh:13:", "node 7 is defined twice (first at line 11)"}));
}

TEST_F(ReadersTest, GmshNanCoordinateIsAnError) {
  const std::string file = write("nan.msh", replace_line(kMsh22, 12, "300 0.1 nan 0.3"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"nan.msh:12:", "expected a finite number for y coordinate of node 300, found 'nan'"}));
}

TEST_F(ReadersTest, Gmsh41InfCoordinateIsAnError) {
  const std::string file = write("inf41.msh", replace_line(kMsh41, 23, "1.6 1.3 -inf"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"inf41.msh:23:", "z coordinate of node 9", "found '-inf'"}));
}

TEST_F(ReadersTest, GmshMalformedCoordinateIsAnError) {
  const std::string file = write("bad.msh", replace_line(kMsh22, 11, "7 1.0abc -0.2 0.3"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"bad.msh:11:", "expected a finite number for x coordinate of node 7, found '1.0abc'"}));
}

TEST_F(ReadersTest, GmshMalformedNodeTagInElementIsAnError) {
  const std::string file = write("bad.msh", replace_line(kMsh22, 21, "4 4 2 1 1 50 7 3x0 12"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"bad.msh:21:", "expected an integer for a node tag of element 4, found '3x0'"}));
}

TEST_F(ReadersTest, GmshWrongNumberOfTetNodesIsAnError) {
  const std::string file = write("three.msh", replace_line(kMsh22, 22, "5 4 2 1 1 7 300 12"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"three.msh:22:", "expected 4 node tags for element 5, found 3"}));
}

TEST_F(ReadersTest, GmshDegenerateTetIsAnError) {
  const std::string file =
      write("flat.msh", replace_line(kMsh22, 14, std::string("9 ") + kFlatNode4));
  // validate_and_orient names the tet by its element tag (5, not its position 1) and line.
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"flat.msh:22:", "element 5 (line 22) is degenerate"}));
}

TEST_F(ReadersTest, GmshQuadraticTetIsAnError) {
  const std::string file =
      write("tet10.msh", replace_line(kMsh22, 22, "5 11 2 1 1 7 300 12 9 50 7 300 12 9 50"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"tet10.msh:22:", "element 5 has type 11 (10-node tetrahedron)", "only 4-node"}));
}

TEST_F(ReadersTest, GmshHexahedronIsAnError) {
  const std::string file =
      write("hex.msh", replace_line(kMsh22, 21, "4 5 2 1 1 50 7 300 12 50 7 300 12"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"hex.msh:21:", "element 4 has type 5 (8-node hexahedron)"}));
}

TEST_F(ReadersTest, GmshUnknownElementTypeIsAnError) {
  const std::string file = write("odd.msh", replace_line(kMsh22, 18, "1 77 2 0 1 50"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"odd.msh:18:", "element 1 has unsupported element type 77"}));
}

TEST_F(ReadersTest, GmshBinaryIsAnError) {
  const std::string file = write("bin.msh", replace_line(kMsh41, 2, "4.1 1 8"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"bin.msh:2:", "binary MSH files are not supported"}));
}

TEST_F(ReadersTest, GmshUnsupportedVersionIsAnError) {
  const std::string file = write("v40.msh", replace_line(kMsh41, 2, "4 0 8"));
  EXPECT_TRUE(
      throws_input_error([&] { read_gmsh(file); },
                         {"v40.msh:2:", "unsupported MSH version '4' (supported: 2.2 and 4.1)"}));
}

TEST_F(ReadersTest, GmshWithoutMeshFormatIsAnError) {
  const std::string file = write("plain.msh", "hello\n");
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"plain.msh:1:", "expected $MeshFormat on the first line"}));
}

TEST_F(ReadersTest, GmshWithoutTetsIsAnError) {
  std::string text = replace_line(kMsh22, 21, "4 2 2 1 1 50 7 300");
  text = replace_line(text, 22, "5 2 2 1 1 7 300 12");
  const std::string file = write("surface.msh", text);
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"surface.msh", "contains no 4-node tetrahedra"}));
}

// Regions and node sets of kMsh41Groups / testing::kTwoRegionMsh (node indices in file
// order).
void expect_reference_groups(const LoadedMesh& loaded) {
  expect_reference_mesh(loaded);
  EXPECT_EQ(loaded.region_names, (std::vector<std::string>{"soft", "bone"}));
  EXPECT_EQ(loaded.tet_region, (std::vector<Index>{0, 1}));
  const NodeSets expected = {
      {"base plate", {0, 1, 2}}, {"soft", {0, 1, 2, 3}}, {"bone", {1, 2, 3, 4}}, {"7", {4}}};
  EXPECT_EQ(loaded.node_sets, expected);
}

TEST_F(ReadersTest, Gmsh41PhysicalGroupsBecomeRegionsAndNodeSets) {
  expect_reference_groups(read_gmsh(write("groups.msh", kMsh41Groups)));
}

TEST_F(ReadersTest, Gmsh22PhysicalGroupsBecomeRegionsAndNodeSets) {
  expect_reference_groups(read_gmsh(write("groups.msh", testing::kTwoRegionMsh)));
}

TEST_F(ReadersTest, GmshWithoutPhysicalVolumesHasNoRegions) {
  const LoadedMesh loaded = read_gmsh(write("mesh.msh", kMsh41));
  EXPECT_TRUE(loaded.region_names.empty());
  EXPECT_TRUE(loaded.tet_region.empty());
  EXPECT_TRUE(loaded.node_sets.empty());
}

TEST_F(ReadersTest, GmshPhysicalNamesMayHoldSpaces) {
  const LoadedMesh loaded = read_gmsh(
      write("names.msh", replace_line(testing::kTwoRegionMsh, 7, "3 1 \"soft  tissue\"")));
  EXPECT_EQ(loaded.region_names[0], "soft  tissue");
}

TEST_F(ReadersTest, GmshTetInTwoRegionsIsAnError) {
  const std::string file =
      write("two.msh", replace_line(kMsh41Groups, 15, "2 0 0 0 2 2 2 2 1 2 0"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"two.msh:40:", "element 4 belongs to the physical volumes 'bone' and 'soft'"}));
}

TEST_F(ReadersTest, GmshTetWithoutRegionBesideOthersIsAnError) {
  const std::string file =
      write("none.msh", replace_line(testing::kTwoRegionMsh, 23, "4 4 2 0 2 7 300 12 9"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"none.msh:23:",
       "element 4 belongs to no physical volume, but element 3 belongs to 'soft'"}));
}

TEST_F(ReadersTest, GmshUnquotedPhysicalNameIsAnError) {
  const std::string file = write("quote.msh", replace_line(testing::kTwoRegionMsh, 6, "2 5 base"));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"quote.msh:6:", "physical name must be in double quotes"}));
}

TEST_F(ReadersTest, GmshGroupElementWithUndefinedNodeIsAnError) {
  const std::string file =
      write("tri.msh", replace_line(testing::kTwoRegionMsh, 21, "2 2 2 5 1 50 7 301"));
  EXPECT_TRUE(
      throws_input_error([&] { read_gmsh(file); },
                         {"tri.msh:21:", "element 2 references node 301, which is not defined"}));
}

// ---- TetGen ----------------------------------------------------------------------------------

TEST_F(ReadersTest, TetgenZeroBasedReadsBackTheMesh) {
  write("zero.node", kTetgenNode0);
  write("zero.ele", kTetgenEle0);
  expect_reference_mesh(read_tetgen(path("zero")));
  expect_reference_mesh(read_tetgen(path("zero.node")));
  expect_reference_mesh(read_tetgen(path("zero.ele")));
}

TEST_F(ReadersTest, TetgenOneBasedReadsBackTheMesh) {
  write("one.node", kTetgenNode1);
  write("one.ele", kTetgenEle1);
  expect_reference_mesh(read_tetgen(path("one")));
}

TEST_F(ReadersTest, TetgenReorientsNegativeTetsAndCountsThem) {
  write("flip.node", kTetgenNode1);
  // Both tets listed with two nodes swapped.
  write("flip.ele", replace_line(replace_line(kTetgenEle1, 3, "1 1 3 2 4"), 4, "2 2 3 5 4"));
  const LoadedMesh loaded = read_tetgen(path("flip"));
  EXPECT_EQ(loaded.reoriented, 2);
  expect_positive_volumes(loaded.mesh);
}

TEST_F(ReadersTest, TetgenTruncatedNodeFileIsAnError) {
  write("cut.node", first_lines(kTetgenNode0, 6));
  write("cut.ele", kTetgenEle0);
  EXPECT_TRUE(throws_input_error(
      [&] { read_tetgen(path("cut")); },
      {"cut.node:6:", "file ends after 3 of the 5 points announced in the header"}));
}

TEST_F(ReadersTest, TetgenTruncatedEleFileIsAnError) {
  write("cut.node", kTetgenNode1);
  write("cut.ele", first_lines(kTetgenEle1, 3));
  EXPECT_TRUE(throws_input_error(
      [&] { read_tetgen(path("cut")); },
      {"cut.ele:3:", "file ends after 1 of the 2 tetrahedra announced in the header"}));
}

TEST_F(ReadersTest, TetgenContentBeyondTheAnnouncedCountIsAnError) {
  write("long.node", kTetgenNode1);
  write("long.ele", std::string(kTetgenEle1) + "3 1 2 3 5\n");
  EXPECT_TRUE(throws_input_error(
      [&] { read_tetgen(path("long")); },
      {"long.ele:5:", "unexpected content after the 2 tetrahedra announced in the header"}));
}

TEST_F(ReadersTest, TetgenUndefinedNodeIsAnError) {
  write("undef.node", kTetgenNode1);
  write("undef.ele", replace_line(kTetgenEle1, 4, "2 2 3 4 6"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_tetgen(path("undef")); },
      {"undef.ele:4:", "tetrahedron 2 references node 6, which is not defined", "1..5"}));
}

TEST_F(ReadersTest, TetgenZeroInOneBasedFileIsAnError) {
  write("zero.node", kTetgenNode1);
  write("zero.ele", replace_line(kTetgenEle1, 3, "1 0 2 3 4"));
  EXPECT_TRUE(
      throws_input_error([&] { read_tetgen(path("zero")); },
                         {"zero.ele:3:", "tetrahedron 1 references node 0, which is not defined"}));
}

TEST_F(ReadersTest, TetgenMisnumberedPointIsAnError) {
  write("gap.node", replace_line(kTetgenNode1, 4, "5 0.1 1.3 0.3"));
  write("gap.ele", kTetgenEle1);
  EXPECT_TRUE(throws_input_error([&] { read_tetgen(path("gap")); },
                                 {"gap.node:4:", "expected point number 3, found 5"}));
}

TEST_F(ReadersTest, TetgenInfCoordinateIsAnError) {
  write("inf.node", replace_line(kTetgenNode0, 7, "3 0.1 inf 1.8 7.5 1"));
  write("inf.ele", kTetgenEle0);
  EXPECT_TRUE(throws_input_error(
      [&] { read_tetgen(path("inf")); },
      {"inf.node:7:", "expected a finite number for y coordinate of node 3, found 'inf'"}));
}

TEST_F(ReadersTest, TetgenMalformedCoordinateIsAnError) {
  write("bad.node", replace_line(kTetgenNode1, 6, "5 1.6 1.3 1.8.1"));
  write("bad.ele", kTetgenEle1);
  EXPECT_TRUE(throws_input_error([&] { read_tetgen(path("bad")); },
                                 {"bad.node:6:", "z coordinate of node 5", "found '1.8.1'"}));
}

TEST_F(ReadersTest, TetgenMissingValueIsAnError) {
  write("few.node", replace_line(kTetgenNode0, 4, "1 1.6 -0.2 0.3 1"));
  write("few.ele", kTetgenEle0);
  EXPECT_TRUE(throws_input_error([&] { read_tetgen(path("few")); },
                                 {"few.node:4:", "expected 6 values for node 1, found 5"}));
}

TEST_F(ReadersTest, TetgenDegenerateTetIsAnError) {
  write("flat.node", replace_line(kTetgenNode1, 6, std::string("5 ") + kFlatNode4));
  write("flat.ele", kTetgenEle1);
  // Named by its number in the 1-based .ele file (2), not its position (1).
  EXPECT_TRUE(throws_input_error([&] { read_tetgen(path("flat")); },
                                 {"flat.ele:4:", "element 2 (line 4) is degenerate"}));
}

TEST_F(ReadersTest, TetgenQuadraticTetIsAnError) {
  write("quad.node", kTetgenNode1);
  write("quad.ele", replace_line(kTetgenEle1, 2, "2 10 0"));
  EXPECT_TRUE(
      throws_input_error([&] { read_tetgen(path("quad")); },
                         {"quad.ele:2:", "10-node (quadratic) tetrahedra are not supported"}));
}

TEST_F(ReadersTest, TetgenMissingEleFileIsAnError) {
  write("lonely.node", kTetgenNode1);
  EXPECT_TRUE(
      throws_input_error([&] { read_tetgen(path("lonely.node")); }, {"lonely.ele", "cannot open"}));
}

// ---- Dispatch by extension -------------------------------------------------------------------

TEST_F(ReadersTest, ReadTetMeshDispatchesOnExtension) {
  expect_reference_mesh(read_tet_mesh(write("a.msh", kMsh41)));
  write("b.node", kTetgenNode0);
  const std::string ele = write("b.ele", kTetgenEle0);
  expect_reference_mesh(read_tet_mesh(ele));
  expect_reference_mesh(read_tet_mesh(path("b.node")));
}

TEST_F(ReadersTest, ReadTetMeshUnknownExtensionIsAnError) {
  const std::string file = write("mesh.stl", "solid x\n");
  EXPECT_TRUE(throws_input_error([&] { read_tet_mesh(file); },
                                 {"mesh.stl", "unknown mesh file extension '.stl'"}));
}

TEST_F(ReadersTest, ReadTetMeshMissingFileIsAnError) {
  const std::string file = path("missing.msh");
  EXPECT_TRUE(throws_input_error([&] { read_tet_mesh(file); }, {"missing.msh", "cannot open"}));
}

// ---- OBJ -------------------------------------------------------------------------------------

TEST_F(ReadersTest, ObjReadsQuadsSlashFormsAndNegativeIndices) {
  const TriSurface surface = read_obj(write("shape.obj", kObj));
  Points V(5, 3);
  V << 0, 0, 0,  //
      1, 0, 0,   //
      1, 1, 0,   //
      0, 1, 0,   //
      0.5, 0.5, 1;
  TriIndices F(6, 3);
  F << 0, 3, 2,  // quad 1 4 3 2 as a fan
      0, 2, 1,   //
      0, 1, 4,   // -5 -4 -1 with 5 vertices defined
      1, 2, 4,   //
      2, 3, 4,   //
      3, 0, 4;
  EXPECT_TRUE(surface.V == V) << surface.V;
  EXPECT_TRUE(surface.F == F) << surface.F;
}

TEST_F(ReadersTest, ObjMalformedNumberIsAnError) {
  const std::string file = write("bad.obj", replace_line(kObj, 5, "v 1 0 0x"));
  EXPECT_TRUE(
      throws_input_error([&] { read_obj(file); },
                         {"bad.obj:5:", "expected a finite number for z of vertex 2, found '0x'"}));
}

TEST_F(ReadersTest, ObjNanCoordinateIsAnError) {
  const std::string file = write("nan.obj", replace_line(kObj, 4, "v nan 0 0"));
  EXPECT_TRUE(
      throws_input_error([&] { read_obj(file); }, {"nan.obj:4:", "x of vertex 1", "found 'nan'"}));
}

TEST_F(ReadersTest, ObjWrongVertexValueCountIsAnError) {
  const std::string file = write("short.obj", replace_line(kObj, 7, "v 0 1"));
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); },
                                 {"short.obj:7:", "vertex 4 needs 3 or 4 numbers", "found 2"}));
}

TEST_F(ReadersTest, ObjIndexZeroIsAnError) {
  const std::string file = write("zero.obj", replace_line(kObj, 13, "f 0 1 2"));
  EXPECT_TRUE(
      throws_input_error([&] { read_obj(file); },
                         {"zero.obj:13:", "face 1 uses vertex index 0; OBJ indices start at 1"}));
}

TEST_F(ReadersTest, ObjIndexOutOfRangeIsAnError) {
  // Vertex 5 is defined only on line 14.
  const std::string file = write("far.obj", replace_line(kObj, 13, "f 1 2 5"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_obj(file); },
      {"far.obj:13:", "face 1 references vertex 5, but 4 vertices are defined so far"}));
}

TEST_F(ReadersTest, ObjNegativeIndexOutOfRangeIsAnError) {
  const std::string file = write("back.obj", replace_line(kObj, 15, "f -6 -4 -1"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_obj(file); },
      {"back.obj:15:", "face 2 references vertex -6, but 5 vertices are defined so far"}));
}

TEST_F(ReadersTest, ObjMalformedIndexIsAnError) {
  const std::string file = write("slash.obj", replace_line(kObj, 16, "f 2/1 3a/1 5/1"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_obj(file); },
      {"slash.obj:16:", "expected an integer for a vertex index of face 3, found '3a'"}));
}

TEST_F(ReadersTest, ObjFaceWithTwoVerticesIsAnError) {
  const std::string file = write("edge.obj", replace_line(kObj, 18, "f 3 4"));
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); },
                                 {"edge.obj:18:", "face 4 has 2 vertices; at least 3 needed"}));
}

TEST_F(ReadersTest, ObjUnknownStatementIsAnError) {
  const std::string file = write("odd.obj", replace_line(kObj, 17, "curv 0 1 1 2"));
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); },
                                 {"odd.obj:17:", "unsupported OBJ statement 'curv'"}));
}

TEST_F(ReadersTest, ObjWithoutFacesIsAnError) {
  const std::string file = write("points.obj", first_lines(kObj, 12));
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); }, {"points.obj", "contains no faces"}));
}

TEST_F(ReadersTest, ObjMissingFileIsAnError) {
  const std::string file = path("missing.obj");
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); }, {"missing.obj", "cannot open"}));
}

// A surface that does not bound a solid is refused with the line of the face at fault.
TEST_F(ReadersTest, ObjOpenSurfaceIsAnError) {
  const std::string file = write("open.obj", first_lines(kObj, 18));  // no face 4 1 5
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); }, {"open.obj:", "the surface is open"}));
}

TEST_F(ReadersTest, ObjNonManifoldEdgeIsAnError) {
  // A fin: a second pyramid side on edge (1 2), which the base and a side already share.
  const std::string file = write("fin.obj", kObj + std::string("v 0.5 -1 0.5\nf 1 6 2\nf 2 6 1\n"));
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); },
                                 {"fin.obj:2", "third face on edge (1 2)", "not manifold"}));
}

TEST_F(ReadersTest, ObjNonManifoldVertexIsAnError) {
  // Two closed pyramids touching at their apex (vertex 5): every edge is shared twice, but the
  // faces around vertex 5 form two fans.
  const std::string file = write("bowtie.obj", kObj + std::string(R"(v 0 0 2
v 1 0 2
v 1 1 2
v 0 1 2
f 6 7 8 9
f 6 5 7
f 7 5 8
f 8 5 9
f 9 5 6
)"));
  EXPECT_TRUE(throws_input_error([&] { read_obj(file); },
                                 {"bowtie.obj:", "vertex 5", "more than one fan"}));
}

TEST_F(ReadersTest, ObjInconsistentOrientationIsAnError) {
  const std::string file = write("flip.obj", replace_line(kObj, 16, "f 2 5 3"));
  EXPECT_TRUE(
      throws_input_error([&] { read_obj(file); }, {"flip.obj:", "not consistently oriented"}));
}

TEST_F(ReadersTest, ObjDegenerateFaceIsAnError) {
  const std::string repeated = write("repeat.obj", replace_line(kObj, 16, "f 2 3 3"));
  EXPECT_TRUE(
      throws_input_error([&] { read_obj(repeated); }, {"repeat.obj:16:", "face 3 is degenerate"}));
  // Apex moved onto the base edge (1 2): the side 1 2 5 has zero area.
  const std::string flat = write("flat.obj", replace_line(kObj, 14, "v 0.5 0 0"));
  EXPECT_TRUE(
      throws_input_error([&] { read_obj(flat); }, {"flat.obj:15:", "face 2 is degenerate"}));
}

TEST_F(ReadersTest, ReadTetMeshExplainsThatObjIsASurface) {
  const std::string file = write("shape.obj", kObj);
  EXPECT_TRUE(throws_input_error([&] { read_tet_mesh(file); },
                                 {"shape.obj", "triangle surface, not a tetrahedral mesh"}));
}

// ---- Checks every reader shares (validate_and_orient) ------------------------------------------

TEST_F(ReadersTest, TetListedTwiceIsAnError) {
  // Element 6 (line 23) repeats element 4 (line 21) with its nodes in another order.
  const std::string file =
      write("twice.msh", replace_line(replace_line(kMsh22, 17, "6"), 22,
                                      "5 4 2 1 1 7 300 12 9\n6 4 2 1 1 12 50 300 7"));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"twice.msh:23:", "element 6 (line 23) repeats the nodes of element 4 (line 21)"}));
}

TEST_F(ReadersTest, OverlappingTetsAreAnError) {
  // Node 4 mirrored through face (1, 2, 3) onto node 0's side: tet 1 folds over tet 0.
  std::string ele = "2 4 0\n0 0 1 2 3\n1 1 2 3 4\n";
  const std::string node =
      write("fold.node", "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 0.1 0.1 0.1\n");
  write("fold.ele", ele);
  EXPECT_TRUE(
      throws_input_error([&] { read_tetgen(node); },
                         {"fold.ele:3:", "element 1 (line 3) overlaps element 0 (line 2)"}));
  // A third tet on face (1, 2, 3).
  write("fold.node", "6 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n5 2 2 2\n");
  write("fold.ele", "3 4 0\n0 0 1 2 3\n1 1 2 3 4\n2 1 2 3 5\n");
  EXPECT_TRUE(throws_input_error([&] { read_tetgen(node); },
                                 {"fold.ele:", "face (1 2 3) belongs to three or more elements"}));
}

TEST_F(ReadersTest, NodeOfNoTetIsAnError) {
  // A sixth node that no element uses, at line 6 of the .node file.
  const std::string node =
      write("stray.node", "6 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n5 9 9 9\n");
  write("stray.ele", "2 4 0\n0 0 1 2 3\n1 1 2 3 4\n");
  EXPECT_TRUE(throws_input_error([&] { read_tetgen(node); },
                                 {"stray.node:7:", "node 5 belongs to no element"}));
}

// ---- Tets overlapping without a shared face (check_no_overlap), in the file's numbering -------

// MSH 2.2 text of `mesh`: node i has the tag 101 + i, tet t the tag tags[t]; tet t is on line
// 9 + #nodes + t.
std::string msh22(const TetMesh& mesh, const std::vector<long long>& tags) {
  std::ostringstream out;
  out << std::setprecision(17) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n"
      << mesh.X.rows() << "\n";
  for (Index i = 0; i < mesh.X.rows(); ++i)
    out << 101 + i << " " << mesh.X(i, 0) << " " << mesh.X(i, 1) << " " << mesh.X(i, 2) << "\n";
  out << "$EndNodes\n$Elements\n" << mesh.tets.rows() << "\n";
  for (Index t = 0; t < mesh.tets.rows(); ++t) {
    out << tags[t] << " 4 2 0 1";
    for (int k = 0; k < 4; ++k) out << " " << 101 + mesh.tets(t, k);
    out << "\n";
  }
  out << "$EndElements\n";
  return out.str();
}

// TetGen NAME.node and NAME.ele of `mesh`, numbered from 1 (tet t on line 2 + t).
void write_tetgen(const std::string& base, const TetMesh& mesh) {
  std::ofstream node(base + ".node"), ele(base + ".ele");
  node << std::setprecision(17) << mesh.X.rows() << " 3 0 0\n";
  for (Index i = 0; i < mesh.X.rows(); ++i)
    node << i + 1 << " " << mesh.X(i, 0) << " " << mesh.X(i, 1) << " " << mesh.X(i, 2) << "\n";
  ele << mesh.tets.rows() << " 4 0\n";
  for (Index t = 0; t < mesh.tets.rows(); ++t) {
    ele << t + 1;
    for (int k = 0; k < 4; ++k) ele << " " << mesh.tets(t, k) + 1;
    ele << "\n";
  }
}

// Element tags 1..n-1 for a mesh's first tets and 57 for its last one, the tet added.
std::vector<long long> tags_with_last(Index num_tets, long long last) {
  std::vector<long long> tags;
  for (Index t = 0; t + 1 < num_tets; ++t) tags.push_back(t + 1);
  tags.push_back(last);
  return tags;
}

// The 2 x 2 x 2 unit box (27 nodes, 48 tets) with one more tet on new nodes: inside the box
// (in no face with another tet), or through its top face.
TetMesh box_and_tet_inside() {
  return testing::joined(testing::box(Vec3::Zero(), Vec3::Ones(), 2),
                         testing::small_tet(Vec3(0.3, 0.2, 0.15), 0.05));
}
TetMesh box_and_tet_sticking_out() {
  return testing::joined(testing::box(Vec3::Zero(), Vec3::Ones(), 2),
                         testing::tet(Vec3(0.4, 0.4, 0.8), Vec3(0.6, 0.4, 0.8), Vec3(0.5, 0.6, 0.8),
                                      Vec3(0.5, 0.5, 1.3)));
}
// The 3 x 3 x 3 unit box without its middle cell: a cavity.
TetMesh box_with_cavity() {
  return testing::without_tets_in(testing::box(Vec3::Zero(), Vec3::Ones(), 3),
                                  Vec3::Constant(1.0 / 3), Vec3::Constant(2.0 / 3));
}

TEST_F(ReadersTest, GmshTetInsideOthersIsAnErrorNamedByItsTag) {
  // The 49th tet, tag 57, on line 9 + 31 + 48 = 88; its nodes have the tags 128..131.
  const std::string file = write("inside.msh", msh22(box_and_tet_inside(), tags_with_last(49, 57)));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"inside.msh:88: element 57 (line 88) overlaps element ",
       "the space just inside its boundary face (1", "is covered by 2 elements"}));
}

TEST_F(ReadersTest, GmshTetStickingOutIsAnErrorNamedByItsTag) {
  const std::string file =
      write("out.msh", msh22(box_and_tet_sticking_out(), tags_with_last(49, 57)));
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(file); },
                                 {"out.msh:88: element 57 (line 88) overlaps element ", "cross"}));
}

TEST_F(ReadersTest, TetgenTetInsideOrStickingOutIsAnErrorNamedByItsNumber) {
  // Numbered from 1: the 49th tet is tetrahedron 49, on line 50 of the .ele file.
  write_tetgen(path("inside"), box_and_tet_inside());
  EXPECT_TRUE(throws_input_error(
      [&] { read_tetgen(path("inside")); },
      {"inside.ele:50: element 49 (line 50) overlaps element ", "is covered by 2 elements"}));
  write_tetgen(path("out"), box_and_tet_sticking_out());
  EXPECT_TRUE(throws_input_error([&] { read_tetgen(path("out")); },
                                 {"out.ele:50: element 49 (line 50) overlaps element ", "cross"}));
}

TEST_F(ReadersTest, MeshWithACavityIsAccepted) {
  const TetMesh hollow = box_with_cavity();
  const std::vector<long long> tags = tags_with_last(static_cast<Index>(hollow.tets.rows()), 999);
  EXPECT_EQ(read_gmsh(write("hollow.msh", msh22(hollow, tags))).mesh.tets.rows(), 26 * 6);
  write_tetgen(path("hollow"), hollow);
  EXPECT_EQ(read_tetgen(path("hollow")).mesh.tets.rows(), 26 * 6);
}

TEST_F(ReadersTest, OverlappingRegionsAreCheckedWhenABodyTakesThemTogether) {
  // Two physical volumes, each a valid body alone: the box (tag 1) and a tet inside it (tag 2).
  std::string text = msh22(box_and_tet_inside(), tags_with_last(49, 57));
  for (Index t = 0; t < 49; ++t) {
    const std::string tag = std::to_string(t < 48 ? t + 1 : 57);
    const size_t at = text.find("\n" + tag + " 4 2 0 1 ") + 1;
    text.replace(at, tag.size() + 9, tag + " 4 2 " + (t < 48 ? "1" : "2") + " 1 ");
  }
  const LoadedMesh loaded = read_gmsh(write("regions.msh", text));
  EXPECT_EQ(loaded.region_names, (std::vector<std::string>{"1", "2"}));
  EXPECT_EQ(select_regions(loaded, {"1"}).mesh.tets.rows(), 48);
  EXPECT_EQ(select_regions(loaded, {"2"}).mesh.tets.rows(), 1);
  EXPECT_TRUE(throws_input_error(
      [&] {
        select_regions(loaded, {"1", "2"});
      },
      {"regions.msh:88: element 57 (line 88) overlaps element "}));
}

// ---- Physical groups whose node sets would be one -------------------------------------------

TEST_F(ReadersTest, GmshSurfaceAndVolumeOfTheSameNameAreAnError) {
  // "base plate" (surface 5) renamed "soft", the name of volume 1.
  const std::string file =
      write("same.msh", replace_line(testing::kTwoRegionMsh, 6, "2 5 \"soft\""));
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"same.msh:7: physical volume 'soft' (tag 1, line 7) and physical surface 'soft' (tag 5, "
       "line 6) have the same name: the node set 'soft' would hold the nodes of both; rename "
       "one"}));
}

TEST_F(ReadersTest, GmshUnnamedGroupsOfTheSameTagAreAnError) {
  // Without $PhysicalNames, the triangle's surface 1 and the tets' volume 1 would both be "1".
  std::string text = replace_line(testing::kTwoRegionMsh, 21, "2 2 2 1 1 50 7 300");
  text = replace_line(text, 4, "$Comment");
  text = replace_line(text, 9, "$EndComment");
  const std::string file = write("unnamed.msh", text);
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"unnamed.msh:22: physical volume 1 (unnamed, line 22) and physical surface 1 (unnamed, line "
       "21) have the same name: the node set '1' would hold the nodes of both; name them in "
       "$PhysicalNames"}));
}

TEST_F(ReadersTest, GmshNamesStoredAsOneAreAnError) {
  // "a/b" and "a_b": the results file writes '/' in a node set's name as '_'.
  std::string text = replace_line(testing::kTwoRegionMsh, 7, "3 1 \"a/b\"");
  text = replace_line(text, 8, "3 2 \"a_b\"");
  const std::string file = write("stored.msh", text);
  EXPECT_TRUE(throws_input_error(
      [&] { read_gmsh(file); },
      {"stored.msh:8: physical volume 'a_b' (tag 2, line 8) and physical volume 'a/b' (tag 1, "
       "line 7) would be stored as the same node set 'a_b' in the results file"}));
}

TEST_F(ReadersTest, GmshPhysicalNameTwiceOrEmptyIsAnError) {
  std::string text = replace_line(testing::kTwoRegionMsh, 8, "3 1 \"bone\"");
  EXPECT_TRUE(
      throws_input_error([&] { read_gmsh(write("twice.msh", text)); },
                         {"twice.msh:8:",
                          "physical group of dimension 3 and tag 1 is named a second time (first "
                          "at line 7)"}));
  text = replace_line(testing::kTwoRegionMsh, 6, "2 5 \"\"");
  EXPECT_TRUE(throws_input_error([&] { read_gmsh(write("empty.msh", text)); },
                                 {"empty.msh:6:", "physical name must not be empty"}));
}

}  // namespace
}  // namespace depthfem
