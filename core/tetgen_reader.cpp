#include "core/tetgen_reader.hpp"

#include <string_view>
#include <vector>

#include "core/overlap_check.hpp"
#include "core/text_parsing.hpp"

namespace depthfem {

namespace {

std::string without_extension(const std::string& path) {
  for (const std::string_view ext : {".node", ".ele"}) {
    if (path.ends_with(ext)) return path.substr(0, path.size() - ext.size());
  }
  return path;
}

// Reads the first line of a .node or .ele file, which must hold `n` non-negative integers.
std::vector<Index> read_header(LineReader& in, size_t n, const char* layout) {
  const auto what = [&] { return "the header (" + std::string(layout) + ")"; };
  if (!in.next()) in.fail("file is empty; expected " + what());
  in.expect_tokens(n, what);
  std::vector<Index> header;
  for (const std::string_view token : in.tokens()) header.push_back(in.to_count(token, what));
  return header;
}

// Advances to record `i` of the `count` records (`noun`) announced in the header.
void next_record(LineReader& in, Index i, Index count, const char* noun) {
  if (!in.next()) {
    in.fail("file ends after " + std::to_string(i) + " of the " + std::to_string(count) + " " +
            noun + " announced in the header");
  }
}

// Throws if anything but comments and blank lines follows the last record.
void expect_file_end(LineReader& in, Index count, const char* noun) {
  if (in.next()) {
    in.fail("unexpected content after the " + std::to_string(count) + " " + noun +
            " announced in the header");
  }
}

// Coordinates of NAME.node, row-major, and the number of its first point (0 or 1).
struct TetgenNodes {
  std::vector<double> xyz;
  std::vector<long> line;  // of each point
  long long first = 0;
};

// "#points 3 #attributes #markers", then "number x y z [attributes] [marker]" per point.
TetgenNodes read_node_file(const std::string& path) {
  LineReader in(path, '#');
  const std::vector<Index> header =
      read_header(in, 4, "#points dimension #attributes #boundary-markers");
  const Index count = header[0], num_attributes = header[2], num_markers = header[3];
  if (header[1] != 3) in.fail("dimension must be 3, found " + std::to_string(header[1]));
  if (num_markers > 1) {
    in.fail("#boundary-markers must be 0 or 1, found " + std::to_string(num_markers));
  }

  TetgenNodes nodes;
  static constexpr const char* kAxis[] = {"x", "y", "z"};
  for (Index i = 0; i < count; ++i) {
    next_record(in, i, count, "points");
    const auto& t = in.tokens();
    const long long number = in.to_integer(t[0], [] { return "a point number"; });
    in.expect_tokens(4 + num_attributes + num_markers,
                     [&] { return "node " + std::to_string(number); });
    if (i == 0) {
      if (number != 0 && number != 1) {
        in.fail("the first point must be numbered 0 or 1, found " + std::to_string(number));
      }
      nodes.first = number;
    } else if (number != nodes.first + i) {
      in.fail("expected point number " + std::to_string(nodes.first + i) + ", found " +
              std::to_string(number));
    }
    for (int k = 0; k < 3; ++k) {
      nodes.xyz.push_back(in.to_double(t[1 + k], [&] {
        return std::string(kAxis[k]) + " coordinate of node " + std::to_string(number);
      }));
    }
    nodes.line.push_back(in.line());
  }
  expect_file_end(in, count, "points");
  return nodes;
}

}  // namespace

LoadedMesh read_tetgen(const std::string& path) {
  const std::string base = without_extension(path);
  const TetgenNodes nodes = read_node_file(base + ".node");
  const long long num_nodes = static_cast<long long>(nodes.xyz.size() / 3);

  // NAME.ele: "#tets nodes-per-tet #attributes", then "number n0 n1 n2 n3 [attributes]" per tet.
  MeshSource source;
  source.file = base + ".ele";
  source.node_file = base + ".node";
  source.node_line = nodes.line;
  for (long long i = 0; i < num_nodes; ++i) source.node_number.push_back(nodes.first + i);
  LineReader in(source.file, '#');
  const std::vector<Index> header =
      read_header(in, 3, "#tetrahedra nodes-per-tetrahedron #attributes");
  const Index count = header[0], num_attributes = header[2];
  if (header[1] == 10) in.fail("10-node (quadratic) tetrahedra are not supported");
  if (header[1] != 4) {
    in.fail("nodes per tetrahedron must be 4, found " + std::to_string(header[1]));
  }

  std::vector<Index> tets;
  for (Index i = 0; i < count; ++i) {
    next_record(in, i, count, "tetrahedra");
    const auto& t = in.tokens();
    const long long number = in.to_integer(t[0], [] { return "a tetrahedron number"; });
    const auto tet = [&] { return "tetrahedron " + std::to_string(number); };
    in.expect_tokens(5 + num_attributes, tet);
    for (int k = 0; k < 4; ++k) {
      const long long node = in.to_integer(t[1 + k], [&] { return "a node of " + tet(); });
      if (node < nodes.first || node >= nodes.first + num_nodes) {
        in.fail(tet() + " references node " + std::to_string(node) + ", which is not defined (" +
                base + ".node numbers its points " + std::to_string(nodes.first) + ".." +
                std::to_string(nodes.first + num_nodes - 1) + ")");
      }
      tets.push_back(static_cast<Index>(node - nodes.first));
    }
    source.tet_line.push_back(in.line());
    source.tet_number.push_back(number);
  }
  expect_file_end(in, count, "tetrahedra");
  LoadedMesh out = finish_loaded_mesh(nodes.xyz, tets, source);
  check_no_overlap(out.mesh, out.source, out.neighbours);
  return out;
}

}  // namespace depthfem
