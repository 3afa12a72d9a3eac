#include "core/results_file.hpp"

#include <hdf5.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/text_parsing.hpp"

namespace depthfem {
namespace {

/// An HDF5 identifier, closed by its own close function (H5Fclose, H5Dclose, ...).
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(Handle&& other) noexcept
      : id_(std::exchange(other.id_, H5I_INVALID_HID)), close_(other.close_) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle& operator=(Handle&&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  hid_t id() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

/// File (little-endian, fixed) and memory (native) HDF5 types of the numbers results files hold.
template <class T>
struct H5Type;
template <>
struct H5Type<double> {
  static hid_t file() { return H5T_IEEE_F64LE; }
  static hid_t memory() { return H5T_NATIVE_DOUBLE; }
};
template <>
struct H5Type<std::int32_t> {
  static hid_t file() { return H5T_STD_I32LE; }
  static hid_t memory() { return H5T_NATIVE_INT32; }
};

/// Copies a variable-length string that HDF5 allocated, then frees it (null reads as "").
std::string take_string(char* value) {
  std::string out = value ? value : "";
  H5free_memory(value);
  return out;
}

/// An open HDF5 file with the checked reads and writes of results files. Objects are named by
/// absolute path ("/steps/000001/x"); every failure throws InputError "FILE: cannot ... OBJECT".
class H5File {
 public:
  /// Creates (truncates) `path` for writing. Keeps HDF5's default (oldest) file format on purpose:
  /// the 1.10 format marks a file open for writing in its superblock, and the file of a killed
  /// run then cannot be opened without `h5clear -s`.
  static H5File create(const std::string& path) {
    const Handle access = unlocked_access(path);
    return H5File(path, H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.id()),
                  "cannot create results file");
  }

  /// Opens `path` read-only.
  static H5File open(const std::string& path) {
    const Handle access = unlocked_access(path);
    if (!std::filesystem::exists(path)) throw InputError(located(path, 0, "no such results file"));
    return H5File(path, H5Fopen(path.c_str(), H5F_ACC_RDONLY, access.id()),
                  "cannot be opened as an HDF5 file");
  }

  /// Throws InputError "FILE: WHAT".
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(located(path_, 0, what));
  }

  /// Writes file buffers and metadata to disk, so that the file is complete as it stands.
  void flush() const { check(H5Fflush(file_.id(), H5F_SCOPE_GLOBAL), "cannot flush"); }

  /// Creates a group that lists its attributes in the order they are written.
  void create_group(const std::string& name) const {
    const std::string what = "cannot create group " + name;
    const Handle properties = handle(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, what);
    check(
        H5Pset_attr_creation_order(properties.id(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED),
        what);
    handle(H5Gcreate2(file_.id(), name.c_str(), H5P_DEFAULT, properties.id(), H5P_DEFAULT),
           H5Gclose, what);
  }

  /// Removes the link `name` (the space of the object is not reclaimed).
  void remove(const std::string& name) const {
    check(H5Ldelete(file_.id(), name.c_str(), H5P_DEFAULT), "cannot remove " + name);
  }

  /// Writes an Eigen vector as a 1D dataset, or a matrix as a 2D row-major dataset.
  template <class Derived>
  void write_array(const std::string& name, const Eigen::MatrixBase<Derived>& a) const {
    using T = typename Derived::Scalar;
    if constexpr (Derived::ColsAtCompileTime == 1) {
      write_raw(name, H5Type<T>::file(), H5Type<T>::memory(), {hsize_t(a.size())},
                a.derived().data());
    } else {
      const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> row_major = a;
      write_raw(name, H5Type<T>::file(), H5Type<T>::memory(),
                {hsize_t(row_major.rows()), hsize_t(row_major.cols())}, row_major.data());
    }
  }

  /// Writes a 1D dataset of variable-length strings.
  void write_strings(const std::string& name, const std::vector<std::string>& values) const {
    std::vector<const char*> pointers;
    for (const std::string& value : values) pointers.push_back(value.c_str());
    const Handle type = string_type("cannot write " + name);
    write_raw(name, type.id(), type.id(), {hsize_t(values.size())}, pointers.data());
  }

  /// Sets a scalar numeric attribute of `object`, replacing any previous value.
  template <class T>
  void set_attribute(const std::string& object, const std::string& name, T value) const {
    write_attribute(object, name, H5Type<T>::file(), H5Type<T>::memory(), &value);
  }

  /// Sets a scalar string attribute of `object`, replacing any previous value.
  void set_string_attribute(const std::string& object, const std::string& name,
                            const std::string& value) const {
    const Handle type = string_type("cannot write attribute " + name + " of " + object);
    const char* pointer = value.c_str();
    write_attribute(object, name, type.id(), type.id(), &pointer);
  }

  /// Whether the link `name` exists (false also when its parent group does not).
  bool exists(const std::string& name) const {
    return H5Lexists(file_.id(), name.c_str(), H5P_DEFAULT) > 0;
  }

  /// Dimensions of dataset `name`.
  std::vector<hsize_t> dims(const std::string& name) const {
    const std::string what = "cannot read " + name;
    const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
    const Handle space = handle(H5Dget_space(set.id()), H5Sclose, what);
    std::vector<hsize_t> out(check(H5Sget_simple_extent_ndims(space.id()), what));
    check(H5Sget_simple_extent_dims(space.id(), out.data(), nullptr), what);
    return out;
  }

  /// All values of dataset `name` as doubles, row-major.
  std::vector<double> read_doubles(const std::string& name) const {
    const std::string what = "cannot read " + name;
    const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
    const Handle space = handle(H5Dget_space(set.id()), H5Sclose, what);
    std::vector<double> out(check(H5Sget_simple_extent_npoints(space.id()), what));
    if (!out.empty())
      check(H5Dread(set.id(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), what);
    return out;
  }

  /// All values of a 1D dataset of variable-length strings.
  std::vector<std::string> read_strings(const std::string& name) const {
    const std::string what = "cannot read " + name;
    const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
    const Handle space = handle(H5Dget_space(set.id()), H5Sclose, what);
    std::vector<char*> raw(check(H5Sget_simple_extent_npoints(space.id()), what), nullptr);
    const Handle type = string_type(what);
    if (!raw.empty())
      check(H5Dread(set.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()), what);
    std::vector<std::string> out;
    for (char* value : raw) out.push_back(take_string(value));
    return out;
  }

  /// Scalar numeric attribute of `object`.
  template <class T>
  T attribute(const std::string& object, const std::string& name) const {
    const std::string what = "cannot read attribute " + name + " of " + object;
    const Handle attr = open_attribute(object, name, what);
    T value{};
    check(H5Aread(attr.id(), H5Type<T>::memory(), &value), what);
    return value;
  }

  /// Scalar string attribute of `object`.
  std::string string_attribute(const std::string& object, const std::string& name) const {
    const std::string what = "cannot read attribute " + name + " of " + object;
    const Handle attr = open_attribute(object, name, what);
    const Handle type = string_type(what);
    char* value = nullptr;
    check(H5Aread(attr.id(), type.id(), &value), what);
    return take_string(value);
  }

  /// Names of the links in `group`, in increasing name order.
  std::vector<std::string> link_names(const std::string& group) const {
    const std::string what = "cannot list " + group;
    H5G_info_t info;
    check(H5Gget_info_by_name(file_.id(), group.c_str(), &info, H5P_DEFAULT), what);
    std::vector<std::string> out;
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      const auto name_of = [&](char* buffer, size_t size) {
        return check(H5Lget_name_by_idx(file_.id(), group.c_str(), H5_INDEX_NAME, H5_ITER_INC, i,
                                        buffer, size, H5P_DEFAULT),
                     what);
      };
      std::string name(name_of(nullptr, 0), '\0');
      name_of(name.data(), name.size() + 1);
      out.push_back(std::move(name));
    }
    return out;
  }

  /// Names of the attributes of `object`, in the order they were written.
  std::vector<std::string> attribute_names(const std::string& object) const {
    std::vector<std::string> out;
    const auto append = [](hid_t, const char* name, const H5A_info_t*, void* names) -> herr_t {
      static_cast<std::vector<std::string>*>(names)->emplace_back(name);
      return 0;
    };
    check(H5Aiterate_by_name(file_.id(), object.c_str(), H5_INDEX_CRT_ORDER, H5_ITER_INC, nullptr,
                             append, &out, H5P_DEFAULT),
          "cannot list the attributes of " + object);
    return out;
  }

 private:
  /// File access without HDF5's file locks, for writing and reading alike: a running
  /// simulation's results file stays readable by other processes (h5py, ParaView, `depthfem info`)
  /// between steps, and HDF5 refuses to reopen an open file with a different locking setting.
  /// Also turns HDF5's printing of error stacks off: failures become exceptions instead.
  static Handle unlocked_access(const std::string& path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    if (access.id() < 0 || H5Pset_file_locking(access.id(), false, true) < 0)
      throw InputError(located(path, 0, "cannot set up HDF5 file access"));
    return access;
  }

  H5File(std::string path, hid_t id, const char* failure)
      : path_(std::move(path)), file_(id, H5Fclose) {
    if (id < 0) fail(failure);
  }

  /// Returns `status`, or throws "FILE: WHAT" when it is negative (HDF5's failure value).
  template <class Status>
  Status check(Status status, const std::string& what) const {
    if (status < 0) fail(what);
    return status;
  }
  Handle handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) const {
    return Handle(check(id, what), close);
  }

  /// Variable-length UTF-8 string type (what h5py reads as str).
  Handle string_type(const std::string& what) const {
    Handle type = handle(H5Tcopy(H5T_C_S1), H5Tclose, what);
    check(H5Tset_size(type.id(), H5T_VARIABLE), what);
    check(H5Tset_cset(type.id(), H5T_CSET_UTF8), what);
    return type;
  }

  void write_raw(const std::string& name, hid_t file_type, hid_t memory_type,
                 const std::vector<hsize_t>& dims, const void* data) const {
    const std::string what = "cannot write " + name;
    const Handle space =
        handle(H5Screate_simple(int(dims.size()), dims.data(), nullptr), H5Sclose, what);
    const Handle set = handle(H5Dcreate2(file_.id(), name.c_str(), file_type, space.id(),
                                         H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                              H5Dclose, what);
    // An empty dataset needs no write (and HDF5 rejects the null buffer of an empty array).
    if (check(H5Sget_simple_extent_npoints(space.id()), what) > 0)
      check(H5Dwrite(set.id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), what);
  }

  void write_attribute(const std::string& object, const std::string& name, hid_t file_type,
                       hid_t memory_type, const void* value) const {
    const std::string what = "cannot write attribute " + name + " of " + object;
    const char* o = object.c_str();
    if (check(H5Aexists_by_name(file_.id(), o, name.c_str(), H5P_DEFAULT), what) > 0)
      check(H5Adelete_by_name(file_.id(), o, name.c_str(), H5P_DEFAULT), what);
    const Handle space = handle(H5Screate(H5S_SCALAR), H5Sclose, what);
    const Handle attr = handle(H5Acreate_by_name(file_.id(), o, name.c_str(), file_type, space.id(),
                                                 H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                               H5Aclose, what);
    check(H5Awrite(attr.id(), memory_type, value), what);
  }

  Handle open_attribute(const std::string& object, const std::string& name,
                        const std::string& what) const {
    return handle(
        H5Aopen_by_name(file_.id(), object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
        H5Aclose, what);
  }

  std::string path_;
  Handle file_;
};

/// Opens a results file for reading, checking that it has the groups every results file has.
H5File open_results(const std::string& path) {
  H5File file = H5File::open(path);
  for (const char* group : {"/mesh", "/run", "/steps"})
    if (!file.exists(group))
      file.fail(std::string("not a depthfem results file (no ") + group + " group)");
  return file;
}

/// "NNNNNN": six digits, so that name order is step order.
std::string step_name(Index index) {
  char name[16];
  std::snprintf(name, sizeof name, "%06d", index);
  return name;
}
/// "/steps/NNNNNN".
std::string step_group(Index index) {
  return "/steps/" + step_name(index);
}

/// A written step, as the XDMF sidecar lists it.
struct SidecarStep {
  Index index = 0;
  double load = 0;
  bool has_velocity = false;
};

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

/// XDMF 3 text of a temporal collection with one tetrahedral grid per step (Time = load), its
/// positions, node depth, cell body and node velocity (when written) taken from `h5_name`.
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
    const std::string group = step_group(step.index);
    out << "      <Grid Name=\"" << step_name(step.index) << "\" GridType=\"Uniform\">\n"
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

struct ResultsFile::State {
  H5File file;
  std::string xmf_path;  ///< the sidecar
  std::string h5_name;   ///< file name of the results file, as the sidecar refers to it
  Index num_nodes = 0, num_tets = 0, num_constraints = 0;
  std::vector<SidecarStep> steps;

  void write_sidecar() const {
    write_file_atomically(xmf_path, xdmf_text(h5_name, num_nodes, num_tets, steps));
  }
};

ResultsFile::ResultsFile(const std::string& path, const Mesh& mesh, const VectorX& depth,
                         const RunInfo& info) {
  const std::filesystem::path fs_path(path);
  if (fs_path.extension() == ".xmf")
    throw InputError(located(path, 0, "a results file must not have the sidecar extension .xmf"));
  if (depth.size() != 0 && depth.size() != mesh.num_nodes())
    throw InputError(located(path, 0,
                             "depth has " + std::to_string(depth.size()) + " values, the mesh " +
                                 std::to_string(mesh.num_nodes()) + " nodes"));
  state_ = std::make_unique<State>(
      State{H5File::create(path),
            std::filesystem::path(fs_path).replace_extension(".xmf").string(),
            fs_path.filename().string(),
            mesh.num_nodes(),
            mesh.num_tets(),
            static_cast<Index>(info.constraint_names.size()),
            {}});
  const H5File& f = state_->file;

  f.create_group("/mesh");
  f.write_array("/mesh/X", mesh.X);
  f.write_array("/mesh/tets", mesh.tets);
  f.write_array("/mesh/tris", mesh.tris);
  f.write_array("/mesh/tet_body", mesh.tet_body);
  f.write_array("/mesh/tri_body", mesh.tri_body);
  f.write_array("/mesh/depth", depth.size() != 0 ? depth : VectorX::Zero(mesh.num_nodes()).eval());
  std::vector<std::string> body_names;
  for (const Body& body : mesh.bodies) body_names.push_back(body.name);
  f.write_strings("/mesh/body_names", body_names);
  if (!mesh.node_sets.empty()) {
    f.create_group("/mesh/node_sets");
    for (const auto& [name, nodes] : mesh.node_sets) {
      std::string object = name;  // '/' would open a subgroup
      std::ranges::replace(object, '/', '_');
      f.write_array("/mesh/node_sets/" + object,
                    Eigen::Map<const IndexVector>(nodes.data(), Eigen::Index(nodes.size())));
    }
  }

  f.create_group("/run");
  f.set_string_attribute("/run", "scene", info.scene_json);
  f.set_string_attribute("/run", "version", info.version);
  f.set_attribute("/run", "threads", info.threads);
  f.set_string_attribute("/run", "analysis", info.analysis);
  f.set_string_attribute("/run", "status", "running");
  f.set_string_attribute("/run", "message", "");
  f.write_strings("/run/constraint_names", info.constraint_names);

  f.create_group("/steps");
  f.flush();
  state_->write_sidecar();
}

ResultsFile::~ResultsFile() = default;

void ResultsFile::append_step(const StepRecord& step) {
  State& s = *state_;
  const H5File& f = s.file;
  const std::string group = step_group(step.index);
  const auto expect_rows = [&](const char* name, Eigen::Index rows, Index expected,
                               const char* of) {
    if (rows != expected)
      f.fail(group + ": " + name + " has " + std::to_string(rows) + " rows, expected " +
             std::to_string(expected) + " (" + of + ")");
  };
  if (step.index < 0 || step.index > 999999)
    f.fail("step index " + std::to_string(step.index) + " is outside 0..999999");
  if (!step.x) f.fail(group + ": no positions x given");
  expect_rows("x", step.x->rows(), s.num_nodes, "#nodes");
  if (step.v) expect_rows("v", step.v->rows(), s.num_nodes, "#nodes");
  expect_rows("reactions", step.reactions.rows(), s.num_constraints, "#constraints");
  if (f.exists(group)) f.fail(group + " was already written");

  f.create_group(group);
  f.set_attribute(group, "index", step.index);
  f.set_attribute(group, "load", step.load);
  f.set_attribute(group, "newton_iterations", step.newton_iterations);
  f.set_attribute(group, "linear_iterations", step.linear_iterations);
  f.set_attribute(group, "energy", step.energy);
  f.set_attribute(group, "seconds", step.seconds);
  if (step.contact_area) f.set_attribute(group, "contact_area", *step.contact_area);
  if (step.contact_force) f.set_attribute(group, "contact_force", *step.contact_force);
  if (step.penetration) f.set_attribute(group, "penetration", *step.penetration);
  f.write_array(group + "/x", *step.x);
  if (step.v) f.write_array(group + "/v", *step.v);
  f.write_array(
      group + "/residuals",
      Eigen::Map<const VectorX>(step.residuals.data(), Eigen::Index(step.residuals.size())));
  f.write_array(group + "/reactions", step.reactions);
  f.flush();

  s.steps.push_back({step.index, step.load, step.v != nullptr});
  s.write_sidecar();
}

void ResultsFile::write_timing(const std::vector<std::pair<std::string, double>>& phases) {
  const H5File& f = state_->file;
  if (f.exists("/timing")) f.remove("/timing");
  f.create_group("/timing");
  for (const auto& [phase, seconds] : phases) f.set_attribute("/timing", phase, seconds);
  f.flush();
}

void ResultsFile::finish(bool success, const std::string& message) {
  const H5File& f = state_->file;
  f.set_string_attribute("/run", "status", success ? "completed" : "failed");
  f.set_string_attribute("/run", "message", message);
  f.flush();
}

ResultsSummary read_results_summary(const std::string& path) {
  const H5File file = open_results(path);
  ResultsSummary out;
  out.num_nodes = static_cast<Index>(file.dims("/mesh/X").at(0));
  out.num_tets = static_cast<Index>(file.dims("/mesh/tets").at(0));
  out.num_tris = static_cast<Index>(file.dims("/mesh/tris").at(0));
  out.body_names = file.read_strings("/mesh/body_names");
  out.analysis = file.string_attribute("/run", "analysis");
  out.status = file.string_attribute("/run", "status");
  out.message = file.string_attribute("/run", "message");
  out.version = file.string_attribute("/run", "version");
  out.threads = file.attribute<int>("/run", "threads");
  const std::vector<std::string> steps = file.link_names("/steps");
  out.num_steps = static_cast<Index>(steps.size());
  for (const std::string& name : steps) {
    const std::string group = "/steps/" + name;
    out.total_newton_iterations += file.attribute<int>(group, "newton_iterations");
    out.total_linear_iterations += file.attribute<int>(group, "linear_iterations");
    out.last_load = file.attribute<double>(group, "load");
  }
  if (file.exists("/timing"))
    for (const std::string& phase : file.attribute_names("/timing"))
      out.timing.emplace_back(phase, file.attribute<double>("/timing", phase));
  return out;
}

Points read_step_positions(const std::string& path, Index step) {
  const H5File file = open_results(path);
  const std::string group = step_group(step);
  if (!file.exists(group)) file.fail("has no step " + std::to_string(step));
  const std::vector<hsize_t> dims = file.dims(group + "/x");
  if (dims.size() != 2 || dims[1] != 3) file.fail(group + "/x is not #nodes x 3");
  return from_row_major<Points>(file.read_doubles(group + "/x"));
}

}  // namespace depthfem
