#include "core/xdmf_writer.hpp"

#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>

#include "core/error.hpp"

namespace depthfem {

namespace {

constexpr const char* kTail = "    </Grid>\n  </Domain>\n</Xdmf>\n";

/// `text` with the XML special characters replaced by entities.
std::string xml_escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// Shortest decimal text that reads back as exactly `value`.
std::string shortest(double value) {
  char buffer[32];
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, value).ptr);
}

/// How an attribute's values lie on the grid, and the XDMF type it is read as.
struct AttributeKind {
  const char* type;    ///< XDMF AttributeType
  const char* center;  ///< Node, Cell or Grid
  int columns;         ///< values per point, cell or grid (0: a scalar, 1D dataset)
};
constexpr AttributeKind kNodeScalar{"Scalar", "Node", 0}, kNodeVector{"Vector", "Node", 3},
    kCellScalar{"Scalar", "Cell", 0}, kCellVector{"Vector", "Cell", 3},
    // Six components pass through both ParaView XDMF readers unchanged (AttributeType Tensor6
    // would be reordered by one of them), and ParaView reads six components as xx, yy, zz, xy,
    // yz, xz.
    kCellSymmetric{"Matrix", "Cell", 6};

/// The values a grid reads from a dataset: rows [first, first + count) of a dataset of `rows`
/// rows of `columns` values (0: one value a row), or of row `step` of a /steps dataset whose
/// rows are such arrays.
struct Part {
  std::string dataset;
  Index rows = 0, first = 0, count = 0;
  int columns = 0;
  Index step = -1;  ///< row of a /steps dataset; -1: the dataset is the array itself

  /// All rows of a dataset that is the array itself.
  static Part whole(std::string dataset, Index rows, int columns) {
    return {std::move(dataset), rows, 0, rows, columns, -1};
  }
};

/// Space-separated numbers.
std::string joined(const std::vector<Index>& values) {
  std::string out;
  for (const Index v : values) out += (out.empty() ? "" : " ") + std::to_string(v);
  return out;
}

/// Appends the XML of one grid of a state.
class GridText {
 public:
  GridText(std::string& out, const SidecarLayout& layout)
      : out_(out), h5_(xml_escaped(layout.h5_name)), dialect_(layout.dialect) {}

  void open(const std::string& name) {
    out_ += "        <Grid Name=\"" + xml_escaped(name) + "\" GridType=\"Uniform\">\n";
  }
  void topology(const char* type, const Part& cells) {
    out_ += "          <Topology TopologyType=\"" + std::string(type) + "\" NumberOfElements=\"" +
            std::to_string(cells.count) + "\">" + item(cells, "Int", 4) + "</Topology>\n";
  }
  void geometry(const Part& nodes) {
    out_ += "          <Geometry GeometryType=\"XYZ\">" + item(nodes, "Float", 8) + "</Geometry>\n";
  }
  /// An attribute read from `values`, of `number` type.
  void attribute(const std::string& name, AttributeKind kind, Part values,
                 const char* number = "Float", int bytes = 8) {
    values.columns = kind.columns;
    out_ += begin_attribute(name, kind) + item(values, number, bytes) + "</Attribute>\n";
  }
  /// A field-data attribute with its values written into the XML.
  void value(const StepValue& v) {
    const bool vector = v.values.size() == 3;
    std::string text;
    for (const double x : v.values) text += (text.empty() ? "" : " ") + shortest(x);
    out_ += begin_attribute(v.name, vector ? AttributeKind{"Vector", "Grid", 3}
                                           : AttributeKind{"Scalar", "Grid", 0}) +
            "<DataItem Dimensions=\"" + (vector ? "1 3" : "1") +
            "\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">" + text +
            "</DataItem></Attribute>\n";
  }
  void close() { out_ += "        </Grid>\n"; }

 private:
  /// The DataItem of `part`: the dataset itself where the part is all of it, else a selection
  /// in the sidecar's dialect. The dimensions of a /steps dataset are stated as they are at
  /// this step (step + 1 rows): ParaView's readers take the part from the dataset as it is
  /// (a row of a /steps dataset is a selection even in its first step: the dataset grows).
  std::string item(const Part& part, const char* number, int bytes) const {
    std::vector<Index> shape{part.count}, start{part.first}, count{part.count}, dims{part.rows};
    if (part.columns) {
      for (std::vector<Index>* v : {&shape, &count, &dims}) v->push_back(part.columns);
      start.push_back(0);
    }
    if (part.step >= 0) {
      start.insert(start.begin(), part.step);
      count.insert(count.begin(), 1);
      dims.insert(dims.begin(), part.step + 1);
    }
    const std::string type = "NumberType=\"" + std::string(number) + "\" Precision=\"" +
                             std::to_string(bytes) + "\" Format=\"HDF\">";
    const std::string source = h5_ + ":" + xml_escaped(part.dataset);
    if (part.step < 0 && part.first == 0 && part.count == part.rows)
      return "<DataItem Dimensions=\"" + joined(shape) + "\" " + type + source + "</DataItem>";
    const std::vector<Index> stride(start.size(), 1);
    if (dialect_ == XdmfDialect::kXdmf3) {
      return "<DataItem Dimensions=\"" + joined(shape) + "\" " + type + source + "|" +
             joined(start) + ":" + joined(stride) + ":" + joined(count) + ":" + joined(dims) +
             "</DataItem>";
    }
    return "<DataItem ItemType=\"HyperSlab\" Dimensions=\"" + joined(shape) +
           "\" Type=\"HyperSlab\"><DataItem Dimensions=\"3 " + std::to_string(start.size()) +
           "\" Format=\"XML\">" + joined(start) + " " + joined(stride) + " " + joined(count) +
           "</DataItem><DataItem Dimensions=\"" + joined(dims) + "\" " + type + source +
           "</DataItem></DataItem>";
  }
  static std::string begin_attribute(const std::string& name, AttributeKind kind) {
    return "          <Attribute Name=\"" + xml_escaped(name) + "\" AttributeType=\"" + kind.type +
           "\" Center=\"" + kind.center + "\">";
  }

  std::string& out_;
  std::string h5_;
  XdmfDialect dialect_;
};

/// A new hidden file ".NAME.XXXXXXXX" beside `path` (named NAME) holding `text`; throws
/// InputError naming `path` when it cannot be written.
NewFile written_beside(const std::string& path, std::string_view text) {
  const std::filesystem::path file(path);
  NewFile out = create_exclusive(file.parent_path(), "." + file.filename().string(), path);
  if (!write_all_at(out.fd.get(), text, 0)) {
    const std::string reason = std::strerror(errno);
    std::error_code ignored;
    std::filesystem::remove(out.path, ignored);
    throw InputError(located(path, 0, "cannot write the XDMF sidecar (" + reason + ")"));
  }
  return out;
}

}  // namespace

XdmfSidecar::XdmfSidecar(std::string path, SidecarLayout layout, const SidecarStep& reference)
    : path_(std::move(path)), layout_(std::move(layout)) {
  std::string text =
      "<?xml version=\"1.0\" ?>\n"
      "<!-- depthfem results: ParaView reads " +
      xml_escaped(layout_.h5_name) +
      (layout_.dialect == XdmfDialect::kXdmf3
           ? " through this file with its Xdmf3 readers (Xdmf3 Reader T names the blocks) -->\n"
           : " through this file with its XDMF Reader -->\n") +
      "<Xdmf Version=\"3.0\">\n  <Domain>\n"
      "    <Grid Name=\"states\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  text += state(reference);
  end_ = static_cast<std::streamoff>(text.size());
  text += kTail;
  NewFile live = written_beside(path_, text);
  std::error_code error;
  std::filesystem::rename(live.path, path_, error);
  if (error) {
    std::filesystem::remove(live.path, error);
    fail("cannot write the XDMF sidecar (" + error.message() + ")");
  }
  live_ = std::move(live.fd);
  NewFile spare = written_beside(path_, text);
  spare_ = std::move(spare.fd);
  spare_path_ = std::move(spare.path);
}

XdmfSidecar::~XdmfSidecar() {
  if (spare_.valid()) ::unlink(spare_path_.c_str());
}

void XdmfSidecar::append(const SidecarStep& step) {
  if (broken_) fail("cannot append to the XDMF sidecar after a failed write");
  const std::string text = state(step);
  const std::string block = text + kTail;
  broken_ = true;  // until both copies hold the step
  if (!write_all_at(spare_.get(), block, end_))
    fail(std::string("cannot append to the XDMF sidecar (") + std::strerror(errno) + ")");
  end_ += static_cast<std::streamoff>(text.size());
  if (::renameat2(AT_FDCWD, spare_path_.c_str(), AT_FDCWD, path_.c_str(), RENAME_EXCHANGE) == 0) {
    std::swap(live_, spare_);
    if (!write_all_at(spare_.get(), block, end_ - static_cast<std::streamoff>(text.size())))
      fail(spare_path_ + ", the spare, cannot be written (" + std::strerror(errno) + ")");
  } else if (errno == EINVAL || errno == ENOSYS || errno == EOPNOTSUPP) {
    // No exchanging rename on this file system: the spare, complete, replaces the sidecar, and
    // a copy of it is the new spare.
    std::error_code error;
    std::filesystem::rename(spare_path_, path_, error);
    if (error) fail("cannot replace the XDMF sidecar (" + error.message() + ")");
    live_ = std::move(spare_);
    std::string copy;
    if (!read_all(live_.get(), copy))
      fail(std::string("cannot read the XDMF sidecar back (") + std::strerror(errno) + ")");
    NewFile spare = written_beside(path_, copy);
    spare_ = std::move(spare.fd);
    spare_path_ = std::move(spare.path);
  } else {
    fail(std::string("cannot exchange the XDMF sidecar with its spare (") + std::strerror(errno) +
         ")");
  }
  broken_ = false;
}

void XdmfSidecar::fail(const std::string& what) const {
  throw InputError(located(path_, 0, what));
}

std::string XdmfSidecar::state(const SidecarStep& step) const {
  const SidecarLayout& l = layout_;
  const ResultFields& f = l.fields;
  const std::string name = step.row < 0 ? "reference" : "step_" + std::to_string(step.row);
  std::string out = "      <Grid Name=\"" + name +
                    "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n" +
                    "        <Time Value=\"" + shortest(step.time) + "\"/>\n";
  // Rows [first, first + count) of a per-node or per-tet field of this state.
  const auto field = [&](const char* dataset, Index rows, Index first, Index count) {
    return step.row < 0 ? Part{std::string("/reference/") + dataset, rows, first, count, 0, -1}
                        : Part{std::string("/steps/") + dataset, rows, first, count, 0, step.row};
  };
  const auto node_field = [&](const char* dataset, const SidecarBlock& b) {
    return field(dataset, l.num_nodes, b.first_node, b.num_nodes);
  };
  const auto tet_field = [&](const char* dataset, const SidecarBlock& b) {
    return field(dataset, l.num_tets, b.first_tet, b.num_tets);
  };
  GridText grid(out, l);
  for (const SidecarBlock& b : l.blocks) {
    grid.open(b.name);
    grid.topology("Tetrahedron", Part::whole(b.tets, b.num_tets, 4));
    Part x = node_field("x", b);
    x.columns = 3;
    grid.geometry(x);
    if (f.displacement) grid.attribute("displacement", kNodeVector, node_field("displacement", b));
    if (f.velocity) grid.attribute("velocity", kNodeVector, node_field("v", b));
    if (l.depth)
      grid.attribute("depth", kNodeScalar,
                     {"/mesh/depth", l.num_nodes, b.first_node, b.num_nodes, 0, -1});
    if (f.stress) {
      grid.attribute("stress", kCellSymmetric, tet_field("stress", b));
      grid.attribute("von_mises", kCellScalar, tet_field("von_mises", b));
    }
    if (f.strain) {
      grid.attribute("strain", kCellSymmetric, tet_field("strain", b));
      grid.attribute("volume_ratio", kCellScalar, tet_field("volume_ratio", b));
    }
    if (f.viscous) grid.attribute("viscous_stress", kCellSymmetric, tet_field("viscous_stress", b));
    grid.close();
  }
  const auto whole = [&](const char* dataset, Index rows) { return field(dataset, rows, 0, rows); };
  grid.open("boundary");
  grid.topology("Triangle", Part::whole("/mesh/tris", l.num_tris, 3));
  Part x = whole("x", l.num_nodes);
  x.columns = 3;
  grid.geometry(x);
  grid.attribute("body", kCellScalar, Part::whole("/mesh/tri_body", l.num_tris, 0), "Int", 4);
  if (f.displacement)
    grid.attribute("displacement", kNodeVector, whole("displacement", l.num_nodes));
  if (l.depth) grid.attribute("depth", kNodeScalar, Part::whole("/mesh/depth", l.num_nodes, 0));
  if (f.contact) {
    grid.attribute("contact_pressure", kCellScalar, whole("contact_pressure", l.num_tris));
    grid.attribute("contact_traction", kCellVector, whole("contact_traction", l.num_tris));
    grid.attribute("contact_gap", kCellScalar, whole("contact_gap", l.num_tris));
    grid.attribute("contact_fraction", kCellScalar, whole("contact_fraction", l.num_tris));
  }
  for (const StepValue& v : step.values) grid.value(v);
  grid.close();
  out += "      </Grid>\n";
  return out;
}

}  // namespace depthfem
