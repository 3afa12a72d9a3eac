#include "core/xdmf_writer.hpp"

#include <charconv>
#include <filesystem>
#include <fstream>

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

/// Appends the XML of one grid of a state.
class GridText {
 public:
  GridText(std::string& out, const std::string& h5_name) : out_(out), h5_(xml_escaped(h5_name)) {}

  void open(const std::string& name) {
    out_ += "        <Grid Name=\"" + xml_escaped(name) + "\" GridType=\"Uniform\">\n";
  }
  void topology(const char* type, Index cells, int corners, const std::string& dataset) {
    out_ += "          <Topology TopologyType=\"" + std::string(type) + "\" NumberOfElements=\"" +
            std::to_string(cells) + "\">" +
            item(std::to_string(cells) + " " + std::to_string(corners), "Int", 4, dataset) +
            "</Topology>\n";
  }
  void geometry(Index nodes, const std::string& dataset) {
    out_ += "          <Geometry GeometryType=\"XYZ\">" +
            item(std::to_string(nodes) + " 3", "Float", 8, dataset) + "</Geometry>\n";
  }
  /// An attribute read from `dataset`, #rows values (x columns) of `number` type.
  void attribute(const std::string& name, AttributeKind kind, Index rows,
                 const std::string& dataset, const char* number = "Float", int bytes = 8) {
    const std::string dims =
        std::to_string(rows) + (kind.columns ? " " + std::to_string(kind.columns) : "");
    out_ += begin_attribute(name, kind) + item(dims, number, bytes, dataset) + "</Attribute>\n";
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
  std::string item(const std::string& dims, const char* number, int bytes,
                   const std::string& dataset) const {
    return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + number + "\" Precision=\"" +
           std::to_string(bytes) + "\" Format=\"HDF\">" + h5_ + ":" + xml_escaped(dataset) +
           "</DataItem>";
  }
  static std::string begin_attribute(const std::string& name, AttributeKind kind) {
    return "          <Attribute Name=\"" + xml_escaped(name) + "\" AttributeType=\"" + kind.type +
           "\" Center=\"" + kind.center + "\">";
  }

  std::string& out_;
  std::string h5_;
};

/// Replaces `path` by `text` through a temporary file and a rename, so that it is never partial.
void write_file_atomically(const std::string& path, const std::string& text) {
  const std::string temporary = path + ".tmp";
  std::ofstream out(temporary, std::ios::trunc);
  out << text;
  out.close();
  std::error_code error;
  if (out) std::filesystem::rename(temporary, path, error);
  if (!out || error) throw InputError(located(path, 0, "cannot write XDMF sidecar"));
}

}  // namespace

XdmfSidecar::XdmfSidecar(std::string path, SidecarLayout layout, const SidecarStep& reference)
    : path_(std::move(path)), layout_(std::move(layout)) {
  std::string text =
      "<?xml version=\"1.0\" ?>\n"
      "<!-- depthfem results: ParaView reads " +
      xml_escaped(layout_.h5_name) +
      " through this file (XDMF Reader, or Xdmf3 Reader T for named blocks) -->\n"
      "<Xdmf Version=\"3.0\">\n  <Domain>\n"
      "    <Grid Name=\"states\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  text += state(reference);
  end_ = static_cast<std::streamoff>(text.size());
  write_file_atomically(path_, text + kTail);
}

void XdmfSidecar::append(const SidecarStep& step) {
  const std::string text = state(step);
  const std::string block = text + kTail;
  std::fstream out(path_, std::ios::in | std::ios::out | std::ios::binary);
  out.seekp(end_);
  out.write(block.data(), static_cast<std::streamsize>(block.size()));
  out.flush();
  if (!out) throw InputError(located(path_, 0, "cannot append to the XDMF sidecar"));
  end_ += static_cast<std::streamoff>(text.size());
}

std::string XdmfSidecar::state(const SidecarStep& step) const {
  const SidecarLayout& l = layout_;
  const ResultFields& f = l.fields;
  const std::string& g = step.group;
  std::string out = "      <Grid Name=\"" + xml_escaped(g.substr(g.rfind('/') + 1)) +
                    "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n" +
                    "        <Time Value=\"" + shortest(step.time) + "\"/>\n";
  GridText grid(out, l.h5_name);
  for (const SidecarBlock& b : l.blocks) {
    const std::string here = g + "/" + b.path;
    grid.open(b.name);
    grid.topology("Tetrahedron", b.num_tets, 4, "/mesh/" + b.path + "tets");
    grid.geometry(b.num_nodes, here + "x");
    if (f.displacement)
      grid.attribute("displacement", kNodeVector, b.num_nodes, here + "displacement");
    if (f.velocity) grid.attribute("velocity", kNodeVector, b.num_nodes, here + "v");
    if (l.depth) grid.attribute("depth", kNodeScalar, b.num_nodes, "/mesh/" + b.path + "depth");
    if (f.stress) {
      grid.attribute("stress", kCellSymmetric, b.num_tets, here + "stress");
      grid.attribute("von_mises", kCellScalar, b.num_tets, here + "von_mises");
    }
    if (f.strain) {
      grid.attribute("strain", kCellSymmetric, b.num_tets, here + "strain");
      grid.attribute("volume_ratio", kCellScalar, b.num_tets, here + "volume_ratio");
    }
    grid.close();
  }
  grid.open("boundary");
  grid.topology("Triangle", l.num_tris, 3, "/mesh/tris");
  grid.geometry(l.num_nodes, g + "/x");
  grid.attribute("body", kCellScalar, l.num_tris, "/mesh/tri_body", "Int", 4);
  if (f.displacement) grid.attribute("displacement", kNodeVector, l.num_nodes, g + "/displacement");
  if (l.depth) grid.attribute("depth", kNodeScalar, l.num_nodes, "/mesh/depth");
  if (f.contact) {
    grid.attribute("contact_pressure", kCellScalar, l.num_tris, g + "/contact_pressure");
    grid.attribute("contact_traction", kCellVector, l.num_tris, g + "/contact_traction");
    grid.attribute("contact_gap", kCellScalar, l.num_tris, g + "/contact_gap");
    grid.attribute("contact_fraction", kCellScalar, l.num_tris, g + "/contact_fraction");
  }
  for (const StepValue& v : step.values) grid.value(v);
  grid.close();
  out += "      </Grid>\n";
  return out;
}

}  // namespace depthfem
