#include "core/obj_reader.hpp"

#include <algorithm>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/text_parsing.hpp"

namespace depthfem {

namespace {
constexpr std::string_view kIgnored[] = {"vn", "vt", "vp", "o", "g", "s", "usemtl", "mtllib", "l"};
}  // namespace

TriSurface read_obj(const std::string& path) {
  LineReader in(path, '#');
  std::vector<double> xyz;
  std::vector<Index> tris;
  std::vector<Index> corners;  // of the current face
  Index num_faces = 0;
  static constexpr const char* kAxis[] = {"x", "y", "z", "w"};
  while (in.next()) {
    const auto& t = in.tokens();
    const std::string_view keyword = t[0];
    if (keyword == "v") {
      const Index vertex = static_cast<Index>(xyz.size() / 3) + 1;
      if (t.size() != 4 && t.size() != 5) {
        in.fail("vertex " + std::to_string(vertex) + " needs 3 or 4 numbers (x y z [w]), found " +
                std::to_string(t.size() - 1));
      }
      for (size_t k = 1; k < t.size(); ++k) {
        const double value = in.to_double(t[k], [&] {
          return std::string(kAxis[k - 1]) + " of vertex " + std::to_string(vertex);
        });
        if (k <= 3) xyz.push_back(value);
      }
    } else if (keyword == "f") {
      ++num_faces;
      const auto face = [&] { return "face " + std::to_string(num_faces); };
      if (t.size() < 4) {
        in.fail(face() + " has " + std::to_string(t.size() - 1) + " vertices; at least 3 needed");
      }
      const long long defined = static_cast<long long>(xyz.size() / 3);
      corners.clear();
      for (size_t k = 1; k < t.size(); ++k) {
        // "a", "a/t", "a//n" or "a/t/n": only the vertex index `a` is used.
        const std::string_view token = t[k].substr(0, t[k].find('/'));
        const long long index = in.to_integer(token, [&] { return "a vertex index of " + face(); });
        if (index == 0) in.fail(face() + " uses vertex index 0; OBJ indices start at 1");
        const long long zero_based = index < 0 ? defined + index : index - 1;
        if (zero_based < 0 || zero_based >= defined) {
          in.fail(face() + " references vertex " + std::to_string(index) + ", but " +
                  std::to_string(defined) + " vertices are defined so far (indices 1.." +
                  std::to_string(defined) + " or -1..-" + std::to_string(defined) + ")");
        }
        corners.push_back(static_cast<Index>(zero_based));
      }
      for (size_t k = 1; k + 1 < corners.size(); ++k) {
        tris.insert(tris.end(), {corners[0], corners[k], corners[k + 1]});
      }
    } else if (std::ranges::find(kIgnored, keyword) == std::end(kIgnored)) {
      in.fail("unsupported OBJ statement '" + std::string(keyword) + "'");
    }
  }
  if (tris.empty()) throw InputError(located(path, 0, "contains no faces"));
  return {from_row_major<Points>(xyz), from_row_major<TriIndices>(tris)};
}

}  // namespace depthfem
