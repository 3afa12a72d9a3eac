#include "core/gmsh_reader.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <span>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"
#include "core/overlap_check.hpp"
#include "core/text_parsing.hpp"

namespace depthfem {

namespace {

using Tokens = std::span<const std::string_view>;

constexpr long long kTet4 = 4;
struct LowerType {
  long long type;
  int dim;
};
// Gmsh element types of dimension 0 to 2 (points, lines, triangles, quadrangles of any order).
constexpr LowerType kLowerDimensionalTypes[] = {
    {1, 1},  {2, 2},  {3, 2},  {8, 1},  {9, 2},  {10, 2}, {15, 0}, {16, 2}, {20, 2},
    {21, 2}, {22, 2}, {23, 2}, {24, 2}, {25, 2}, {26, 1}, {27, 1}, {28, 1}};
struct VolumeType {
  long long type;
  const char* name;
};
// Gmsh volume element types other than the 4-node tetrahedron: rejected with their name.
constexpr VolumeType kOtherVolumeTypes[] = {
    {5, "8-node hexahedron"},    {6, "6-node prism"},         {7, "5-node pyramid"},
    {11, "10-node tetrahedron"}, {12, "27-node hexahedron"},  {13, "18-node prism"},
    {14, "14-node pyramid"},     {17, "20-node hexahedron"},  {18, "15-node prism"},
    {19, "13-node pyramid"},     {29, "20-node tetrahedron"}, {30, "35-node tetrahedron"},
    {31, "56-node tetrahedron"}, {92, "64-node hexahedron"},  {93, "125-node hexahedron"}};

enum class MshVersion { v2_2, v4_1 };

// (dimension, tag) of a physical group or of an elementary entity.
using DimTag = std::pair<int, long long>;

// An element of dimension 0 to 2 that may belong to physical groups (its nodes form node sets).
struct LowerElement {
  DimTag key;  // MSH 2.2: (dim, physical tag); MSH 4.1: (dim, entity tag)
  long long tag;
  long line;
  size_t first, count;  // its node tags in MshContent::lower_node_tags
};

// Everything read so far; elements keep node tags until the whole file is read, because Gmsh
// allows $Elements before $Nodes (and $Entities after $Elements).
struct MshContent {
  std::vector<double> xyz;
  std::unordered_map<long long, Index> node_of_tag;
  MeshSource source;
  std::vector<long long> tet_node_tags;  // 4 per tet (their element tags: source.tet_number)
  std::vector<long long> tet_key;        // MSH 2.2: physical tag (0: none); MSH 4.1: entity tag
  std::vector<LowerElement> lower;
  std::vector<long long> lower_node_tags;
  std::map<DimTag, std::string> physical_names;               // $PhysicalNames
  std::map<DimTag, long> physical_name_line;                  // line of each $PhysicalNames entry
  std::map<DimTag, std::vector<long long>> entity_physicals;  // MSH 4.1 $Entities
  bool has_nodes = false, has_elements = false;
};

std::string quoted(std::string_view token) {
  return "'" + std::string(token) + "'";
}

// Advances to entry `read` of the `expected` ones (`noun`) of a section; throws when the file or
// the section ends first.
void next_entry(LineReader& in, const char* section, const char* noun, Index expected, Index read) {
  const auto progress = [&] {
    return " (expected " + std::to_string(expected) + " " + noun + ", read " +
           std::to_string(read) + ")";
  };
  if (!in.next()) in.fail(std::string("file ends inside $") + section + progress());
  if (in.tokens()[0].starts_with('$')) {
    in.fail(std::string("$") + section + " ends early at " + quoted(in.tokens()[0]) + progress());
  }
}

// Reads the "$EndSECTION" line that must follow the announced entries.
void expect_section_end(LineReader& in, const std::string& section) {
  const std::string end = "$End" + section;
  if (!in.next()) in.fail("file ends inside $" + section + " (no " + end + ")");
  if (in.tokens().size() != 1 || in.tokens()[0] != end) {
    in.fail("expected " + end + " after the announced entries, found " + quoted(in.tokens()[0]));
  }
}

// Skips a section this reader does not use ($PhysicalNames, $Entities, $NodeData, ...).
void skip_section(LineReader& in, const std::string& section) {
  const long start = in.line();
  const std::string end = "$End" + section;
  while (in.next()) {
    if (in.tokens()[0] == end) return;
  }
  in.fail("file ends inside $" + section + " (started at line " + std::to_string(start) + ", no " +
          end + ")");
}

// Reads "version file-type data-size" and "$EndMeshFormat".
MshVersion read_mesh_format(LineReader& in) {
  if (!in.next()) in.fail("file ends inside $MeshFormat");
  in.expect_tokens(3, [] { return "$MeshFormat (version file-type data-size)"; });
  const auto& t = in.tokens();
  const double version = in.to_double(t[0], [] { return "the MSH version"; });
  const long long file_type = in.to_integer(t[1], [] { return "the MSH file type"; });
  if (file_type == 1) in.fail("binary MSH files are not supported; save the mesh as ASCII");
  if (file_type != 0) in.fail("MSH file type must be 0 (ASCII), found " + quoted(t[1]));
  MshVersion result = MshVersion::v2_2;
  if (version == 4.1) {
    result = MshVersion::v4_1;
  } else if (version != 2.2) {
    in.fail("unsupported MSH version " + quoted(t[0]) + " (supported: 2.2 and 4.1)");
  }
  expect_section_end(in, "MeshFormat");
  return result;
}

void add_node(LineReader& in, MshContent& msh, long long tag, Tokens xyz) {
  const auto [it, inserted] =
      msh.node_of_tag.emplace(tag, static_cast<Index>(msh.node_of_tag.size()));
  if (!inserted) {
    in.fail("node " + std::to_string(tag) + " is defined twice (first at line " +
            std::to_string(msh.source.node_line[it->second]) + ")");
  }
  static constexpr const char* kAxis[] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    msh.xyz.push_back(in.to_double(xyz[k], [&] {
      return std::string(kAxis[k]) + " coordinate of node " + std::to_string(tag);
    }));
  }
  msh.source.node_line.push_back(in.line());
  msh.source.node_number.push_back(tag);
}

// Keeps a 4-node tetrahedron and, where it may belong to a physical group, a lower-dimensional
// element; rejects every other type. `key` is the physical tag (MSH 2.2, 0 for none) or the
// entity tag (MSH 4.1) of the element.
void add_element(LineReader& in, MshContent& msh, long long tag, long long type, long long key,
                 bool key_is_entity, Tokens nodes) {
  const auto element = [&] { return "element " + std::to_string(tag); };
  if (type != kTet4) {
    const auto* lower = std::ranges::find(kLowerDimensionalTypes, type, &LowerType::type);
    if (lower != std::end(kLowerDimensionalTypes)) {
      if (!key_is_entity && key == 0) return;  // MSH 2.2 element in no physical group
      msh.lower.push_back({{lower->dim, key}, tag, in.line(), msh.lower_node_tags.size(), 0});
      for (const std::string_view node : nodes) {
        msh.lower_node_tags.push_back(
            in.to_integer(node, [&] { return "a node tag of " + element(); }));
      }
      msh.lower.back().count = nodes.size();
      return;
    }
    const auto* volume = std::ranges::find(kOtherVolumeTypes, type, &VolumeType::type);
    if (volume == std::end(kOtherVolumeTypes)) {
      in.fail(element() + " has unsupported element type " + std::to_string(type));
    }
    in.fail(element() + " has type " + std::to_string(type) + " (" + volume->name +
            "); only 4-node tetrahedra (type 4) are supported");
  }
  if (nodes.size() != 4) {
    in.fail("expected 4 node tags for " + element() + ", found " + std::to_string(nodes.size()));
  }
  for (const std::string_view node : nodes) {
    msh.tet_node_tags.push_back(in.to_integer(node, [&] { return "a node tag of " + element(); }));
  }
  msh.source.tet_number.push_back(tag);
  msh.tet_key.push_back(key);
  msh.source.tet_line.push_back(in.line());
}

// Reads a count line: the first line of $Nodes or $Elements in MSH 2.2.
Index read_count(LineReader& in, const std::string& section) {
  const auto what = [&] { return "the number of entries in $" + section; };
  if (!in.next()) in.fail("file ends inside $" + section);
  in.expect_tokens(1, what);
  return in.to_count(in.tokens()[0], what);
}

// MSH 2.2: "n", then n lines "tag x y z".
void read_nodes_v2(LineReader& in, MshContent& msh) {
  const Index count = read_count(in, "Nodes");
  for (Index i = 0; i < count; ++i) {
    next_entry(in, "Nodes", "nodes", count, i);
    in.expect_tokens(4, [] { return "a node (tag x y z)"; });
    const auto& t = in.tokens();
    add_node(in, msh, in.to_integer(t[0], [] { return "a node tag"; }), Tokens(t).subspan(1));
  }
  expect_section_end(in, "Nodes");
}

// MSH 2.2: "n", then n lines "tag type #tags tags... nodes...".
void read_elements_v2(LineReader& in, MshContent& msh) {
  const Index count = read_count(in, "Elements");
  for (Index i = 0; i < count; ++i) {
    next_entry(in, "Elements", "elements", count, i);
    const Tokens t = in.tokens();
    if (t.size() < 3) in.fail("expected an element (tag type #tags tags... nodes...)");
    const long long tag = in.to_integer(t[0], [] { return "an element tag"; });
    const auto element = [&] { return "element " + std::to_string(tag); };
    const long long type = in.to_integer(t[1], [&] { return "the type of " + element(); });
    const Index num_tags = in.to_count(t[2], [&] { return "the number of tags of " + element(); });
    if (t.size() < 3 + static_cast<size_t>(num_tags)) {
      in.fail(element() + " announces " + std::to_string(num_tags) +
              " tags but the line has only " + std::to_string(t.size() - 3) + " values after them");
    }
    // The first tag is the physical group (0: none), the second the elementary entity.
    const long long physical =
        num_tags > 0 ? in.to_integer(t[3], [&] { return "the physical tag of " + element(); }) : 0;
    add_element(in, msh, tag, type, physical, false, t.subspan(3 + num_tags));
  }
  expect_section_end(in, "Elements");
}

// MSH 4.1: "#blocks #nodes min-tag max-tag", then per block "dim entity parametric n", n tag
// lines and n coordinate lines "x y z [u [v [w]]]".
void read_nodes_v4(LineReader& in, MshContent& msh) {
  if (!in.next()) in.fail("file ends inside $Nodes");
  const auto header = [] { return "the $Nodes header (#blocks #nodes min-tag max-tag)"; };
  in.expect_tokens(4, header);
  const Index num_blocks = in.to_count(in.tokens()[0], header);
  const Index count = in.to_count(in.tokens()[1], header);
  Index read = 0;
  std::vector<long long> tags;
  for (Index b = 0; b < num_blocks; ++b) {
    next_entry(in, "Nodes", "nodes", count, read);
    const auto block = [] { return "a node block header (dim entity parametric #nodes)"; };
    in.expect_tokens(4, block);
    const Index dim = in.to_count(in.tokens()[0], block);
    const Index parametric = in.to_count(in.tokens()[2], block);
    const Index n = in.to_count(in.tokens()[3], block);
    if (dim > 3 || parametric > 1) {
      in.fail("invalid node block header: dimension must be 0..3 and parametric 0 or 1");
    }
    tags.clear();
    for (Index i = 0; i < n; ++i) {
      next_entry(in, "Nodes", "nodes", count, read);
      in.expect_tokens(1, [] { return "a node tag"; });
      tags.push_back(in.to_integer(in.tokens()[0], [] { return "a node tag"; }));
    }
    for (Index i = 0; i < n; ++i) {
      next_entry(in, "Nodes", "nodes", count, read);
      in.expect_tokens(3 + (parametric ? dim : 0),
                       [&] { return "the coordinates of node " + std::to_string(tags[i]); });
      add_node(in, msh, tags[i], in.tokens());
      ++read;
    }
  }
  if (read != count) {
    in.fail("the node blocks hold " + std::to_string(read) + " nodes but $Nodes announced " +
            std::to_string(count));
  }
  expect_section_end(in, "Nodes");
}

// MSH 4.1: "#blocks #elements min-tag max-tag", then per block "dim entity type n" and n lines
// "tag nodes...".
void read_elements_v4(LineReader& in, MshContent& msh) {
  if (!in.next()) in.fail("file ends inside $Elements");
  const auto header = [] { return "the $Elements header (#blocks #elements min-tag max-tag)"; };
  in.expect_tokens(4, header);
  const Index num_blocks = in.to_count(in.tokens()[0], header);
  const Index count = in.to_count(in.tokens()[1], header);
  Index read = 0;
  for (Index b = 0; b < num_blocks; ++b) {
    next_entry(in, "Elements", "elements", count, read);
    const auto block = [] { return "an element block header (dim entity type #elements)"; };
    in.expect_tokens(4, block);
    const long long entity = in.to_integer(in.tokens()[1], block);
    const long long type = in.to_integer(in.tokens()[2], block);
    const Index n = in.to_count(in.tokens()[3], block);
    for (Index i = 0; i < n; ++i, ++read) {
      next_entry(in, "Elements", "elements", count, read);
      const Tokens t = in.tokens();
      add_element(in, msh, in.to_integer(t[0], [] { return "an element tag"; }), type, entity, true,
                  t.subspan(1));
    }
  }
  if (read != count) {
    in.fail("the element blocks hold " + std::to_string(read) +
            " elements but $Elements announced " + std::to_string(count));
  }
  expect_section_end(in, "Elements");
}

// "n", then n lines "dim tag \"name\"" (the name may contain spaces).
void read_physical_names(LineReader& in, MshContent& msh) {
  const Index count = read_count(in, "PhysicalNames");
  for (Index i = 0; i < count; ++i) {
    next_entry(in, "PhysicalNames", "names", count, i);
    const Tokens t = in.tokens();
    const auto what = [] { return "a physical name (dim tag \"name\")"; };
    if (t.size() < 3) in.fail("expected a physical name (dim tag \"name\")");
    const long long dim = in.to_integer(t[0], what);
    const long long tag = in.to_integer(t[1], what);
    const std::string_view name(t[2].data(), t.back().data() + t.back().size() - t[2].data());
    if (dim < 0 || dim > 3) in.fail("physical group dimension must be 0..3, found " + quoted(t[0]));
    if (name.size() < 2 || name.front() != '"' || name.back() != '"')
      in.fail("physical name must be in double quotes, found " + quoted(name));
    if (name.size() == 2) in.fail("physical name must not be empty");
    const DimTag key{static_cast<int>(dim), tag};
    if (const auto it = msh.physical_name_line.find(key); it != msh.physical_name_line.end()) {
      in.fail("physical group of dimension " + std::to_string(dim) + " and tag " +
              std::to_string(tag) + " is named a second time (first at line " +
              std::to_string(it->second) + ")");
    }
    msh.physical_names[key] = std::string(name.substr(1, name.size() - 2));
    msh.physical_name_line[key] = in.line();
  }
  expect_section_end(in, "PhysicalNames");
}

// MSH 4.1: "#points #curves #surfaces #volumes", then one line per entity: its tag, its
// coordinates (points: x y z; others: a bounding box of six numbers), its physical tags
// ("n tag..."), and for curves, surfaces and volumes the bounding entities.
void read_entities(LineReader& in, MshContent& msh) {
  if (!in.next()) in.fail("file ends inside $Entities");
  const auto header = [] { return "the $Entities header (#points #curves #surfaces #volumes)"; };
  in.expect_tokens(4, header);
  Index counts[4];
  for (int d = 0; d < 4; ++d) counts[d] = in.to_count(in.tokens()[d], header);
  for (int dim = 0; dim < 4; ++dim) {
    for (Index i = 0; i < counts[dim]; ++i) {
      next_entry(in, "Entities", "entities", counts[dim], i);
      const Tokens t = in.tokens();
      const size_t at = dim == 0 ? 4 : 7;  // position of the number of physical tags
      const auto what = [&] { return "an entity of dimension " + std::to_string(dim); };
      if (t.size() <= at) in.fail("expected " + what() + " (tag, coordinates, physical tags)");
      const long long tag = in.to_integer(t[0], what);
      const Index n = in.to_count(t[at], what);
      if (t.size() < at + 1 + static_cast<size_t>(n))
        in.fail(what() + " announces " + std::to_string(n) + " physical tags but lists fewer");
      std::vector<long long>& physicals = msh.entity_physicals[{dim, tag}];
      for (Index k = 0; k < n; ++k) {
        // Gmsh writes a negative tag for a group whose orientation is reversed.
        physicals.push_back(std::abs(in.to_integer(t[at + 1 + k], what)));
      }
    }
  }
  expect_section_end(in, "Entities");
}

// Physical tags of an element with `key` (see LowerElement::key). A MSH 4.1 entity that
// $Entities does not list has none.
std::vector<long long> physical_tags(const MshContent& msh, MshVersion version, const DimTag& key) {
  if (version == MshVersion::v2_2) {
    if (key.second == 0) return {};
    return {key.second};
  }
  const auto it = msh.entity_physicals.find(key);
  return it != msh.entity_physicals.end() ? it->second : std::vector<long long>{};
}

// Name of a physical group: its $PhysicalNames entry, else its tag.
std::string physical_name(const MshContent& msh, int dim, long long tag) {
  const auto it = msh.physical_names.find({dim, tag});
  return it != msh.physical_names.end() ? it->second : std::to_string(tag);
}

constexpr const char* kDimensionNames[] = {"point", "curve", "surface", "volume"};

// A physical group that elements use, where it is defined: the line of its $PhysicalNames entry,
// else of its first element.
struct UsedGroup {
  DimTag group;
  long line;
  bool named;
};

// "physical surface 'name' (tag T)", or "physical surface T (unnamed)".
std::string describe(const MshContent& msh, const UsedGroup& g) {
  const std::string kind =
      std::string("physical ") + kDimensionNames[g.group.first] + " " +
      (g.named ? "'" + msh.physical_names.at(g.group) + "' (tag " + std::to_string(g.group.second)
               : std::to_string(g.group.second) + " (unnamed");
  return kind + ", line " + std::to_string(g.line) + ")";
}

// Every physical group becomes a node set named after it, so two groups that elements use must
// not have the same name (a surface and a volume called "fixed", or an unnamed surface and an
// unnamed volume with the same tag, would make one set of the nodes of both), nor names that the
// results file stores as one (stored_set_name).
void check_group_names(const MshContent& msh, MshVersion version) {
  std::map<DimTag, UsedGroup> used;
  const auto use = [&](int dim, long long tag, long element_line) {
    const DimTag group{dim, tag};
    const auto named = msh.physical_name_line.find(group);
    const bool is_named = named != msh.physical_name_line.end();
    used.try_emplace(group, UsedGroup{group, is_named ? named->second : element_line, is_named});
  };
  for (size_t t = 0; t < msh.tet_key.size(); ++t)
    for (long long tag : physical_tags(msh, version, {3, msh.tet_key[t]}))
      use(3, tag, msh.source.tet_line[t]);
  for (const LowerElement& e : msh.lower)
    for (long long tag : physical_tags(msh, version, e.key)) use(e.key.first, tag, e.line);

  std::vector<UsedGroup> groups;
  for (const auto& [group, g] : used) groups.push_back(g);
  std::ranges::stable_sort(groups, {}, &UsedGroup::line);
  std::map<std::string, const UsedGroup*> by_name, by_stored_name;
  for (const UsedGroup& g : groups) {
    const std::string name = physical_name(msh, g.group.first, g.group.second);
    const auto fail = [&](const UsedGroup& first, const std::string& why) {
      throw InputError(located(msh.source.file, g.line,
                               describe(msh, g) + " and " + describe(msh, first) + why));
    };
    if (const auto [it, fresh] = by_name.emplace(name, &g); !fresh) {
      fail(*it->second,
           " have the same name: the node set '" + name + "' would hold the nodes of both; " +
               (g.named && it->second->named ? "rename one" : "name them in $PhysicalNames"));
    }
    if (const auto [it, fresh] = by_stored_name.emplace(stored_set_name(name), &g); !fresh) {
      fail(*it->second, " would be stored as the same node set '" + stored_set_name(name) +
                            "' in the results file ('/' becomes '_'); rename one");
    }
  }
}

// Regions from the physical volumes of the tets, and node sets from every physical group.
void add_groups(const MshContent& msh, MshVersion version, const std::vector<Index>& tets,
                LoadedMesh& out) {
  check_group_names(msh, version);
  const std::string& file = msh.source.file;
  const Index num_tets = static_cast<Index>(msh.source.tet_number.size());
  std::map<long long, std::string> volume_names;  // physical tag -> name, in tag order
  std::vector<std::string> tet_name(static_cast<size_t>(num_tets));
  Index with = -1, without = -1;  // a tet with a region and one without
  for (Index t = 0; t < num_tets; ++t) {
    std::set<std::string> names;
    for (long long tag : physical_tags(msh, version, {3, msh.tet_key[t]})) {
      names.insert(physical_name(msh, 3, tag));
      volume_names.emplace(tag, physical_name(msh, 3, tag));
    }
    const auto element = "element " + std::to_string(msh.source.tet_number[t]);
    if (names.size() > 1) {
      throw InputError(located(file, msh.source.tet_line[t],
                               element + " belongs to the physical volumes '" + *names.begin() +
                                   "' and '" + *std::next(names.begin()) +
                                   "'; a tet may belong to one region only"));
    }
    if (names.empty()) {
      without = t;
    } else {
      with = t;
      tet_name[t] = *names.begin();
    }
  }
  if (with >= 0 && without >= 0) {
    throw InputError(located(file, msh.source.tet_line[without],
                             "element " + std::to_string(msh.source.tet_number[without]) +
                                 " belongs to no physical volume, but element " +
                                 std::to_string(msh.source.tet_number[with]) + " belongs to '" +
                                 tet_name[with] + "': give every tet a region or none"));
  }
  std::map<std::string, std::set<Index>> sets;
  if (with >= 0) {
    for (const auto& [tag, name] : volume_names) {
      if (std::ranges::find(out.region_names, name) == out.region_names.end())
        out.region_names.push_back(name);
    }
    out.tet_region.resize(static_cast<size_t>(num_tets));
    for (Index t = 0; t < num_tets; ++t) {
      out.tet_region[t] = static_cast<Index>(std::ranges::find(out.region_names, tet_name[t]) -
                                             out.region_names.begin());
      sets[tet_name[t]].insert(tets.begin() + 4 * t, tets.begin() + 4 * t + 4);
    }
  }
  for (const LowerElement& e : msh.lower) {
    const std::vector<long long> tags = physical_tags(msh, version, e.key);
    if (tags.empty()) continue;
    std::vector<Index> nodes;
    for (size_t k = e.first; k < e.first + e.count; ++k) {
      const auto it = msh.node_of_tag.find(msh.lower_node_tags[k]);
      if (it == msh.node_of_tag.end()) {
        throw InputError(located(file, e.line,
                                 "element " + std::to_string(e.tag) + " references node " +
                                     std::to_string(msh.lower_node_tags[k]) +
                                     ", which is not defined"));
      }
      nodes.push_back(it->second);
    }
    for (long long tag : tags)
      sets[physical_name(msh, e.key.first, tag)].insert(nodes.begin(), nodes.end());
  }
  for (auto& [name, nodes] : sets) out.node_sets[name].assign(nodes.begin(), nodes.end());
}

}  // namespace

LoadedMesh read_gmsh(const std::string& path) {
  LineReader in(path);
  if (!in.next() || in.tokens()[0] != "$MeshFormat") {
    in.fail("not a Gmsh MSH file: expected $MeshFormat on the first line");
  }
  const MshVersion version = read_mesh_format(in);
  MshContent msh;
  msh.source.file = path;
  while (in.next()) {
    const std::string_view head = in.tokens()[0];
    if (head == "$Nodes") {
      if (msh.has_nodes) in.fail("second $Nodes section");
      msh.has_nodes = true;
      if (version == MshVersion::v2_2) {
        read_nodes_v2(in, msh);
      } else {
        read_nodes_v4(in, msh);
      }
    } else if (head == "$Elements") {
      if (msh.has_elements) in.fail("second $Elements section");
      msh.has_elements = true;
      if (version == MshVersion::v2_2) {
        read_elements_v2(in, msh);
      } else {
        read_elements_v4(in, msh);
      }
    } else if (head == "$PhysicalNames" && in.tokens().size() == 1) {
      read_physical_names(in, msh);
    } else if (head == "$Entities" && in.tokens().size() == 1 && version == MshVersion::v4_1) {
      read_entities(in, msh);
    } else if (head.starts_with('$') && !head.starts_with("$End") && in.tokens().size() == 1) {
      skip_section(in, std::string(head.substr(1)));
    } else {
      in.fail("expected a section such as $Nodes or $Elements, found " + quoted(head));
    }
  }
  if (!msh.has_nodes) throw InputError(located(path, 0, "has no $Nodes section"));
  if (!msh.has_elements) throw InputError(located(path, 0, "has no $Elements section"));

  std::vector<Index> tets(msh.tet_node_tags.size());
  for (size_t i = 0; i < tets.size(); ++i) {
    const auto it = msh.node_of_tag.find(msh.tet_node_tags[i]);
    if (it == msh.node_of_tag.end()) {
      throw InputError(located(path, msh.source.tet_line[i / 4],
                               "element " + std::to_string(msh.source.tet_number[i / 4]) +
                                   " references node " + std::to_string(msh.tet_node_tags[i]) +
                                   ", which is not defined"));
    }
    tets[i] = it->second;
  }
  LoadedMesh out = finish_loaded_mesh(msh.xyz, tets, msh.source);
  add_groups(msh, version, tets, out);
  if (out.region_names.empty()) check_no_overlap(out.mesh, out.source, out.neighbours);
  return out;
}

}  // namespace depthfem
