#include "core/xdmf_writer.hpp"

#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"

namespace depthfem {

namespace {

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

}  // namespace

std::string xdmf_text(const std::string& h5_name, Index num_nodes, Index num_tets,
                      const std::vector<SidecarStep>& steps) {
  const std::string nodes = std::to_string(num_nodes), tets = std::to_string(num_tets);
  const auto item = [&](const std::string& dims, const char* type, int bytes,
                        const std::string& dataset) {
    return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + type + "\" Precision=\"" +
           std::to_string(bytes) + "\" Format=\"HDF\">" + xml_escaped(h5_name) + ":" + dataset +
           "</DataItem>";
  };
  std::ostringstream out;
  out << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n"
      << "    <Grid Name=\"steps\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const SidecarStep& step : steps) {
    const std::string& group = step.group;
    out << "      <Grid Name=\"" << step.name << "\" GridType=\"Uniform\">\n"
        << "        <Time Value=\"" << shortest(step.load) << "\"/>\n"
        << "        <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"" << tets << "\">"
        << item(tets + " 4", "Int", 4, "/mesh/tets") << "</Topology>\n"
        << "        <Geometry GeometryType=\"XYZ\">" << item(nodes + " 3", "Float", 8, group + "/x")
        << "</Geometry>\n"
        << "        <Attribute Name=\"depth\" AttributeType=\"Scalar\" Center=\"Node\">"
        << item(nodes, "Float", 8, "/mesh/depth") << "</Attribute>\n"
        << "        <Attribute Name=\"body\" AttributeType=\"Scalar\" Center=\"Cell\">"
        << item(tets, "Int", 4, "/mesh/tet_body") << "</Attribute>\n";
    if (step.has_velocity)
      out << "        <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">"
          << item(nodes + " 3", "Float", 8, group + "/v") << "</Attribute>\n";
    out << "      </Grid>\n";
  }
  out << "    </Grid>\n  </Domain>\n</Xdmf>\n";
  return out.str();
}

void write_file_atomically(const std::string& path, const std::string& text) {
  const std::string temporary = path + ".tmp";
  std::ofstream out(temporary, std::ios::trunc);
  out << text;
  out.close();
  std::error_code error;
  if (out) std::filesystem::rename(temporary, path, error);
  if (!out || error) throw InputError(located(path, 0, "cannot write XDMF sidecar"));
}

}  // namespace depthfem
