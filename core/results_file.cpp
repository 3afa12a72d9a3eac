#include "core/results_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <utility>

#include "core/error.hpp"
#include "core/exclusive_file.hpp"
#include "core/hdf5_file.hpp"
#include "core/xdmf_writer.hpp"

namespace depthfem {
namespace {

/// Bytes of the fixed-length strings: /run/status, /run/message, /timing/phases.
constexpr size_t kStatusBytes = 16, kMessageBytes = 4096, kPhaseBytes = 64;

/// Opens a results file for reading, checking that it has the groups every results file has.
H5File open_results(const std::string& path) {
  H5File file = H5File::open(path);
  for (const char* group : {"/mesh", "/run", "/steps"})
    if (!file.exists(group))
      file.fail(std::string("not a depthfem results file (no ") + group + " group)");
  if (!file.exists("/steps/index"))
    file.fail("was written by an older depthfem (steps as groups), which this version cannot read");
  return file;
}

/// In a shape a reader expects: any number of rows (or values) in this dimension.
constexpr hsize_t kAny = ~hsize_t(0);

/// "12 x 3", "scalar".
std::string shape_text(const std::vector<hsize_t>& dims) {
  std::string out = dims.empty() ? "scalar" : "";
  for (size_t k = 0; k < dims.size(); ++k) out += (k ? " x " : "") + std::to_string(dims[k]);
  return out;
}

/// What a dataset of values of class `type` holds, for messages.
std::string class_text(H5T_class_t type) {
  switch (type) {
    case H5T_INTEGER:
      return "integers";
    case H5T_FLOAT:
      return "floating-point numbers";
    case H5T_STRING:
      return "strings";
    default:
      return "values of neither a number nor a string type";
  }
}

/// The dimensions of dataset `name`, which must hold values of class `type` (H5T_INTEGER,
/// H5T_FLOAT or H5T_STRING) in as many dimensions as `shape` has, equal to those of `shape` that
/// are not kAny; throws naming the file and the dataset, with `expected` (the shape in words:
/// "#nodes x 3"), when it does not.
std::vector<hsize_t> checked_dims(const H5File& file, const std::string& name, H5T_class_t type,
                                  const std::vector<hsize_t>& shape, const std::string& expected) {
  if (!file.exists(name)) file.fail("has no dataset " + name);
  const H5T_class_t actual = file.type_class(name);
  if (actual != type)
    file.fail(name + " holds " + class_text(actual) + ", not " + class_text(type));
  const std::vector<hsize_t> dims = file.dims(name);
  bool fits = dims.size() == shape.size();
  for (size_t k = 0; fits && k < dims.size(); ++k) fits = shape[k] == kAny || shape[k] == dims[k];
  if (!fits) file.fail(name + " has shape " + shape_text(dims) + ", not " + expected);
  return dims;
}

/// The number of rows of a dataset of `columns` values of class `type` per row, which must be at
/// most the largest Index; throws naming the file and the dataset otherwise.
Index checked_rows(const H5File& file, const std::string& name, H5T_class_t type, hsize_t columns,
                   const std::string& expected) {
  const hsize_t rows = checked_dims(file, name, type, {kAny, columns}, expected)[0];
  if (rows > hsize_t(std::numeric_limits<Index>::max()))
    file.fail(name + " has " + std::to_string(rows) + " rows, more than depthfem can index");
  return static_cast<Index>(rows);
}

/// `value`, read from dataset `name`, as a whole number in [least, most]; throws naming the file
/// and the dataset when it is not one (NaN, 1e300, 2.5).
long long whole_number(const H5File& file, const std::string& name, double value, long long least,
                       long long most) {
  if (!(value >= double(least) && value <= double(most) && value == std::floor(value))) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", value);
    file.fail(name + " holds " + text + ", not a whole number from " + std::to_string(least) +
              " to " + std::to_string(most));
  }
  return static_cast<long long>(value);
}

/// `value`, read from dataset `name` (`what`: which value), checked finite; throws naming the file
/// and the dataset otherwise.
double finite_number(const H5File& file, const std::string& name, double value,
                     const std::string& what) {
  if (!std::isfinite(value)) file.fail(name + " holds a value that is not finite (" + what + ")");
  return value;
}

/// The number of completed steps: the rows of /steps/index (a list of integers, at most
/// kMaxSteps of them).
hsize_t num_steps(const H5File& file) {
  const hsize_t n =
      checked_dims(file, "/steps/index", H5T_INTEGER, {kAny}, "one value per step")[0];
  if (n > hsize_t(kMaxSteps))
    file.fail("/steps/index has " + std::to_string(n) + " rows, more than the " +
              std::to_string(kMaxSteps) + " steps a results file holds");
  return n;
}

/// The step indices of the completed steps of a results file, in row order: whole numbers from 0,
/// each above the one before.
std::vector<Index> step_indices(const H5File& file) {
  const std::vector<double> values = file.read_rows("/steps/index", 0, num_steps(file));
  std::vector<Index> out;
  for (const double value : values) {
    const Index index = static_cast<Index>(
        whole_number(file, "/steps/index", value, 0, std::numeric_limits<Index>::max()));
    if (!out.empty() && index <= out.back())
      file.fail("/steps/index holds step " + std::to_string(index) + " after step " +
                std::to_string(out.back()) + ", not in increasing order");
    out.push_back(index);
  }
  return out;
}

/// The row of step `step` in the /steps datasets; throws naming the file when it has no such step.
hsize_t step_row(const H5File& file, const std::vector<Index>& indices, Index step) {
  const auto at = std::ranges::lower_bound(indices, step);
  if (at == indices.end() || *at != step)
    file.fail("has no step " + std::to_string(step) +
              (indices.empty() ? std::string(" (no completed steps)")
                               : " (steps " + std::to_string(indices.front()) + " to " +
                                     std::to_string(indices.back()) + ")"));
  return hsize_t(at - indices.begin());
}

/// The one string of a scalar dataset of a fixed-length string (/run/status, /run/message).
std::string one_text(const H5File& file, const std::string& name) {
  checked_dims(file, name, H5T_STRING, {}, "one string (scalar)");
  const std::vector<std::string> texts = file.read_texts(name);
  if (texts.size() != 1) file.fail(name + " holds " + std::to_string(texts.size()) + " strings");
  return texts[0];
}

/// The sidecar's blocks: one per body, named after it and its materials, except that a body with
/// several element regions has one per region, named "BODY/REGION (material)", with the body's
/// nodes and the region's tets. A single block is the whole mesh; several have their own tets
/// (/mesh/blocks/<k>/tets, with block-local node indices).
std::vector<SidecarBlock> sidecar_blocks(const Mesh& mesh, const RunInfo& info) {
  const auto named = [](const std::string& name, const std::vector<std::string>& materials,
                        size_t k) {
    return k < materials.size() ? name + " (" + materials[k] + ")" : name;
  };
  std::vector<SidecarBlock> blocks;
  size_t region = 0;  // index of the body's first region among the regions of all bodies
  for (size_t b = 0; b < mesh.bodies.size(); ++b) {
    const Body& body = mesh.bodies[b];
    if (body.regions.size() < 2) {
      blocks.push_back({named(body.name, info.body_materials, b), "/mesh/tets", body.num_nodes,
                        body.num_tets, body.first_node, body.first_tet});
    } else {
      for (size_t r = 0; r < body.regions.size(); ++r) {
        const Region& here = body.regions[r];
        blocks.push_back({named(body.name + "/" + here.name, info.region_materials, region + r),
                          "/mesh/tets", body.num_nodes, here.num_tets, body.first_node,
                          here.first_tet});
      }
    }
    region += body.regions.size();
  }
  if (blocks.size() > 1)
    for (size_t k = 0; k < blocks.size(); ++k)
      blocks[k].tets = "/mesh/blocks/" + std::to_string(k) + "/tets";
  return blocks;
}

/// Pressure, traction, gap and contact fraction per boundary triangle from the step's sums,
/// per unit of the triangle's current area A (so that their integrals over the boundary are
/// the sums): pressure = magnitude / A, traction = force / A, gap = depth integral / contact
/// area (0 without contact), fraction = contact area / A.
struct SurfaceFields {
  VectorX pressure, gap, fraction;
  Eigen::Matrix<double, Eigen::Dynamic, 3> traction;
};
SurfaceFields surface_fields(const TriIndices& tris, const Points& x, const SurfaceContact& s) {
  const Index n = static_cast<Index>(tris.rows());
  SurfaceFields out{VectorX::Zero(n), VectorX::Zero(n), VectorX::Zero(n),
                    Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(n, 3)};
  for (Index f = 0; f < n; ++f) {
    const Vec3 a = x.row(tris(f, 0)), b = x.row(tris(f, 1)), c = x.row(tris(f, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (!(area > 0) || !(s.area(f) > 0)) continue;
    out.pressure(f) = s.magnitude(f) / area;
    out.traction.row(f) = s.force.row(f) / area;
    out.gap(f) = s.depth_integral(f) / s.area(f);
    out.fraction(f) = s.area(f) / area;
  }
  return out;
}

/// The values a step shows in ParaView as field data.
std::vector<StepValue> step_values(const StepRecord& step, bool velocity,
                                   const std::vector<std::string>& constraint_names) {
  std::vector<StepValue> out{{"step", {double(step.index)}},
                             {"load", {step.load}},
                             {"settling", {double(step.settling)}},
                             {"newton_iterations", {double(step.newton_iterations)}},
                             {"linear_iterations", {double(step.linear_iterations)}},
                             {"linear_solves", {double(step.linear_solves)}},
                             {"factorizations", {double(step.factorizations)}},
                             {"residual", {step.residuals.empty() ? 0.0 : step.residuals.back()}},
                             {"energy", {step.energy}}};
  if (velocity) out.push_back({"kinetic_energy", {step.kinetic_energy}});
  for (size_t k = 0; k < constraint_names.size(); ++k) {
    const auto r = step.reactions.row(Eigen::Index(k));
    out.push_back({"reaction " + constraint_names[k], {r(0), r(1), r(2)}});
  }
  if (!step.contact.empty()) out.push_back({"contact_area", {step.contact_area()}});
  if (step.penetration) out.push_back({"penetration", {*step.penetration}});
  if (step.dissipated_energy) out.push_back({"dissipated_energy", {*step.dissipated_energy}});
  for (const InterfaceForce& c : step.contact) {
    out.push_back({"contact_force " + c.name, {c.force(0), c.force(1), c.force(2)}});
    out.push_back({"contact_force_magnitude " + c.name, {c.magnitude}});
    out.push_back({"contact_area " + c.name, {c.area}});
  }
  return out;
}

/// The sidecars of results file `path`: NAME.xmf for ParaView's Xdmf3 readers (its default for
/// .xmf), NAME.xdmf2 for its older XDMF Reader; the two readers take different notations for a
/// part of a dataset.
std::vector<std::pair<std::filesystem::path, XdmfDialect>> sidecar_paths(
    const std::filesystem::path& path) {
  return {{std::filesystem::path(path).replace_extension(".xmf"), XdmfDialect::kXdmf3},
          {std::filesystem::path(path).replace_extension(".xdmf2"), XdmfDialect::kXdmf2}};
}

}  // namespace

std::vector<std::string> results_sidecars(const std::string& path) {
  std::vector<std::string> out;
  for (const auto& [sidecar, dialect] : sidecar_paths(path)) out.push_back(sidecar.string());
  return out;
}
std::string results_lock_path(const std::string& path) {
  const std::filesystem::path file(path);
  return (file.parent_path() / ("." + file.filename().string() + ".lock")).string();
}

// The writer's lock on a results file: the hidden file ".NAME.lock" beside it holds an
// exclusive flock and the writer's process id while the run writes, so that a second run with
// the same --out is refused before it truncates the file. Removed with the writer. The lock file
// is never reached through a link, and a file of that name holding anything but a process id is
// not a lock file: it is left as it is and the run refused.
class WriterLock {
 public:
  WriterLock(const std::string& path, std::string lock_path) : lock_path_(std::move(lock_path)) {
    const auto refuse = [&](const std::string& why) { throw InputError(located(path, 0, why)); };
    fd_ =
        FileDescriptor(::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644));
    if (!fd_.valid()) {
      refuse(errno == ELOOP
                 ? "the lock file " + lock_path_ +
                       " is a symbolic link; a run makes its lock file itself (remove "
                       "the link)"
                 : "cannot create the lock file " + lock_path_ + " (" + std::strerror(errno) + ")");
    }
    struct stat status {};
    if (fstat(fd_.get(), &status) != 0 || !S_ISREG(status.st_mode) || status.st_nlink != 1)
      refuse("the lock file " + lock_path_ +
             " is not a plain file of its own (a special file or one with other links); remove "
             "it");
    device_ = status.st_dev;
    inode_ = status.st_ino;
    char text[32] = {};
    const ssize_t n = pread(fd_.get(), text, sizeof text - 1, 0);
    const std::string_view held(text, n > 0 ? size_t(n) : 0);
    if (n < 0 || n >= 24 || !std::ranges::all_of(held, [](char c) { return c >= '0' && c <= '9'; }))
      refuse(lock_path_ + " is not a depthfem lock file (it holds more than a process id); " +
             "remove it or choose another --out");
    if (flock(fd_.get(), LOCK_EX | LOCK_NB) != 0) {
      fd_ = FileDescriptor();
      refuse("is being written by another depthfem run (process " + std::string(held) +
             "); wait for it to end or choose another --out");
    }
    const std::string pid = std::to_string(getpid());
    if (ftruncate(fd_.get(), 0) != 0 || pwrite(fd_.get(), pid.data(), pid.size(), 0) < 0) {
      fd_ = FileDescriptor();
      refuse("cannot write the lock file " + lock_path_);
    }
  }
  WriterLock(WriterLock&&) noexcept = default;
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;
  WriterLock& operator=(WriterLock&&) = delete;
  ~WriterLock() {
    // Removed before the lock is released, and only while it is still this lock's file.
    struct stat status {};
    if (fd_.valid() && lstat(lock_path_.c_str(), &status) == 0 && status.st_dev == device_ &&
        status.st_ino == inode_)
      ::unlink(lock_path_.c_str());
  }

 private:
  std::string lock_path_;
  FileDescriptor fd_;
  dev_t device_ = 0;
  ino_t inode_ = 0;
};

/// The datasets of a step, as rows of /steps/NAME: how many values a row has in each dimension
/// (none for a scalar).
struct StepDataset {
  std::string name;
  hid_t type;
  std::vector<hsize_t> row;
};

struct ResultsFile::State {
  WriterLock lock;  // taken before anything is written
  H5File file;
  Points X;  ///< reference positions, for displacements
  Index num_tets = 0;
  TriIndices tris;
  RunInfo info;
  bool depth = false;  ///< the run has material-depth contact (and reports penetration)
  std::vector<XdmfSidecar> sidecars = {};
  Index num_steps = 0;
  Index last_index = -1;
  Index settling_steps = 0;
  hsize_t num_residuals = 0;
  hsize_t step_reserve = 0;  ///< bytes a step may add to the file, besides its residuals

  Index num_nodes() const { return static_cast<Index>(X.rows()); }

  /// Throws naming the step when it does not fit the run: out of order, past kMaxSteps, arrays
  /// of other sizes, other contact interfaces.
  void check_step(const StepRecord& step, const Points& x, const Points* v,
                  const ElementFields* elements, const RestartRecord* restart) const;
  /// Writes every dataset of the step at the next row and its restart record into a slot, then
  /// its index (a reader counts the rows of /steps/index, so a step is in the file once its
  /// index is), each flushed; returns the row.
  hsize_t write_rows(const StepRecord& step, const Points& x, const Points* v,
                     const ElementFields* elements, const RestartRecord* restart) const;

  /// Every dataset of /steps this run writes.
  std::vector<StepDataset> step_datasets() const {
    const ResultFields& f = info.fields;
    const hsize_t nodes = hsize_t(num_nodes()), tets = hsize_t(num_tets),
                  triangles = hsize_t(tris.rows()), interfaces = info.contact_names.size();
    const hid_t i32 = H5Type<std::int32_t>::file(), f64 = H5Type<double>::file();
    std::vector<StepDataset> out{{"index", i32, {}},
                                 {"load", f64, {}},
                                 {"settling", i32, {}},
                                 {"newton_iterations", i32, {}},
                                 {"linear_iterations", i32, {}},
                                 {"linear_solves", i32, {}},
                                 {"factorizations", i32, {}},
                                 {"energy", f64, {}},
                                 {"seconds", f64, {}},
                                 {"residual_count", i32, {}},
                                 {"residuals", f64, {}},
                                 {"reactions", f64, {info.constraint_names.size(), 3}},
                                 {"x", f64, {nodes, 3}}};
    if (f.velocity) {
      out.push_back({"kinetic_energy", f64, {}});
      out.push_back({"v", f64, {nodes, 3}});
    }
    if (f.displacement) out.push_back({"displacement", f64, {nodes, 3}});
    if (interfaces > 0) {
      out.push_back({"contact_area", f64, {}});
      out.push_back({"contact_forces", f64, {interfaces, 3}});
      out.push_back({"contact_force_magnitudes", f64, {interfaces}});
      out.push_back({"contact_areas", f64, {interfaces}});
    }
    if (depth) out.push_back({"penetration", f64, {}});
    if (f.stress) {
      out.push_back({"stress", f64, {tets, 6}});
      out.push_back({"von_mises", f64, {tets}});
    }
    if (f.strain) {
      out.push_back({"strain", f64, {tets, 6}});
      out.push_back({"volume_ratio", f64, {tets}});
    }
    if (f.viscous) {
      out.push_back({"dissipated_energy", f64, {}});
      out.push_back({"viscous_stress", f64, {tets, 6}});
    }
    if (f.contact) {
      out.push_back({"contact_pressure", f64, {triangles}});
      out.push_back({"contact_traction", f64, {triangles, 3}});
      out.push_back({"contact_gap", f64, {triangles}});
      out.push_back({"contact_fraction", f64, {triangles}});
    }
    return out;
  }
};

namespace {

/// Refuses what the writer cannot store: a results path with a sidecar's extension, per-node
/// arrays of another length, node-set names that would be stored as one.
void check_writable(const std::string& path, const Mesh& mesh, const VectorX& depth,
                    const RunInfo& info) {
  const std::filesystem::path fs_path(path);
  for (const auto& [sidecar, dialect] : sidecar_paths(fs_path))
    if (fs_path.extension() == sidecar.extension())
      throw InputError(located(
          path, 0,
          "a results file must not have the sidecar extension " + sidecar.extension().string()));
  if (depth.size() != 0 && depth.size() != mesh.num_nodes())
    throw InputError(located(path, 0,
                             "depth has " + std::to_string(depth.size()) + " values, the mesh " +
                                 std::to_string(mesh.num_nodes()) + " nodes"));
  if (info.fields.velocity && info.initial_velocity.rows() != mesh.num_nodes())
    throw InputError(located(path, 0,
                             "the initial velocity has " +
                                 std::to_string(info.initial_velocity.rows()) + " rows, the mesh " +
                                 std::to_string(mesh.num_nodes()) + " nodes"));
  std::map<std::string, std::string> stored;  // stored name -> node set
  for (const auto& [set_name, nodes] : mesh.node_sets) {
    const auto [it, fresh] = stored.emplace(stored_set_name(set_name), set_name);
    if (!fresh)
      throw InputError(located(path, 0,
                               "node sets '" + it->second + "' and '" + set_name +
                                   "' would both be stored as '" + it->first + "'"));
  }
}

/// A new hidden name ".NAME.partial.XXXXXXXX" beside results file `path` that no file has yet:
/// the file is built under it and takes its own name once readers can open it (in SWMR mode),
/// so that a file of that name is always readable, even when the writer is killed.
std::string staging_path(const std::filesystem::path& path) {
  const std::string prefix =
      (path.parent_path() / ("." + path.filename().string() + ".partial")).string();
  std::string staging = random_name(prefix);
  std::error_code unused;
  for (int k = 0;
       k < 32 && std::filesystem::exists(std::filesystem::symlink_status(staging, unused)); ++k)
    staging = random_name(prefix);
  return staging;
}

/// /mesh: the scene's nodes, tets, boundary, bodies, regions, node sets and the sidecar blocks'
/// tets.
void write_mesh(const H5File& f, const Mesh& mesh, const VectorX& depth, const RunInfo& info,
                const std::vector<SidecarBlock>& blocks) {
  f.create_group("/mesh");
  f.write_array("/mesh/X", mesh.X);
  f.write_array("/mesh/tets", mesh.tets);
  f.write_array("/mesh/tris", mesh.tris);
  f.write_array("/mesh/tet_body", mesh.tet_body);
  f.write_array("/mesh/tri_body", mesh.tri_body);
  f.write_array("/mesh/tri_tet", mesh.tri_tet);
  if (depth.size() != 0) f.write_array("/mesh/depth", depth);
  std::vector<std::string> body_names;
  for (const Body& body : mesh.bodies) body_names.push_back(body.name);
  f.write_strings("/mesh/body_names", body_names);
  f.write_strings("/mesh/body_materials", info.body_materials);
  IndexVector tet_region = IndexVector::Constant(mesh.num_tets(), -1);
  std::vector<std::string> region_names;
  for (const Body& body : mesh.bodies) {
    for (const Region& r : body.regions) {
      tet_region.segment(r.first_tet, r.num_tets).setConstant(Index(region_names.size()));
      region_names.push_back(r.name);
    }
  }
  f.write_array("/mesh/tet_region", tet_region);
  f.write_strings("/mesh/region_names", region_names);
  f.write_strings("/mesh/region_materials", info.region_materials);
  if (!mesh.node_sets.empty()) {
    f.create_group("/mesh/node_sets");
    for (const auto& [set_name, nodes] : mesh.node_sets) {
      f.write_array("/mesh/node_sets/" + stored_set_name(set_name),
                    Eigen::Map<const IndexVector>(nodes.data(), Eigen::Index(nodes.size())));
    }
  }
  if (blocks.size() > 1) {
    f.create_group("/mesh/blocks");
    for (const SidecarBlock& block : blocks) {
      const std::string group = block.tets.substr(0, block.tets.rfind('/'));
      f.create_group(group);
      f.set_string_attribute(group, "name", block.name);
      const TetIndices local =
          (mesh.tets.middleRows(block.first_tet, block.num_tets).array() - block.first_node)
              .matrix();
      f.write_array(block.tets, local);
    }
  }
}

/// /run: the scene, version, threads, ranks, analysis, status "running", the reaction and contact
/// rows' names.
void write_run(const H5File& f, const RunInfo& info) {
  f.create_group("/run");
  f.set_string_attribute("/run", "scene", info.scene_json);
  f.set_string_attribute("/run", "version", info.version);
  f.set_attribute("/run", "threads", info.threads);
  f.set_attribute("/run", "ranks", info.ranks);
  f.set_string_attribute("/run", "analysis", info.analysis);
  f.create_text("/run/status", kStatusBytes);
  f.write_text("/run/status", "running");
  f.create_text("/run/message", kMessageBytes);
  f.write_strings("/run/constraint_names", info.constraint_names);
  f.write_strings("/run/contact_names", info.contact_names);
}

/// /reference: the state the first step starts from, with the fields every step will hold.
void write_reference(const H5File& f, const Mesh& mesh, const RunInfo& info) {
  const ResultFields& fields = info.fields;
  const hsize_t nodes = hsize_t(mesh.num_nodes()), tets = hsize_t(mesh.num_tets()),
                tris = hsize_t(mesh.num_tris());
  f.create_group("/reference");
  f.create_row_view("/reference/x", "/mesh/X", 0, nodes);
  if (fields.displacement) f.create_zeros("/reference/displacement", {nodes, 3});
  if (fields.velocity) f.write_array("/reference/v", info.initial_velocity);
  if (fields.stress) {
    f.create_zeros("/reference/stress", {tets, 6});
    f.create_zeros("/reference/von_mises", {tets});
  }
  if (fields.strain) {
    f.create_zeros("/reference/strain", {tets, 6});
    f.write_array("/reference/volume_ratio", VectorX::Ones(mesh.num_tets()).eval());
  }
  if (fields.viscous) f.create_zeros("/reference/viscous_stress", {tets, 6});
  if (fields.contact) {
    for (const char* field : {"contact_pressure", "contact_gap", "contact_fraction"})
      f.create_zeros(std::string("/reference/") + field, {tris});
    f.create_zeros("/reference/contact_traction", {tris, 3});
  }
}

/// The slots of the restart record: the last two written steps' (see write_rows).
constexpr hsize_t kRestartSlots = 2;

/// /restart with its two slots, each marked empty (step -1), when the run writes a restart
/// record; returns the bytes a step's record may add to the file.
hsize_t create_restart_datasets(const H5File& f, const RestartLayout& layout, Index nodes,
                                Index tets) {
  if (layout.empty()) return 0;
  f.create_group("/restart");
  f.create_rows("/restart/step", H5Type<std::int32_t>::file(), {});
  for (hsize_t slot = 0; slot < kRestartSlots; ++slot)
    f.write_row("/restart/step", slot, std::int32_t(-1));
  hsize_t bytes = 0;
  if (layout.acceleration) {
    f.create_rows("/restart/acceleration", H5Type<double>::file(), {hsize_t(nodes), 3});
    bytes += hsize_t(nodes) * 3 * sizeof(double);
  }
  if (layout.force) {
    f.create_rows("/restart/force", H5Type<double>::file(), {hsize_t(nodes), 3});
    bytes += hsize_t(nodes) * 3 * sizeof(double);
  }
  if (layout.history_columns > 0) {
    f.create_rows("/restart/history", H5Type<double>::file(),
                  {hsize_t(tets), hsize_t(layout.history_columns)});
    bytes += hsize_t(tets) * hsize_t(layout.history_columns) * sizeof(double);
  }
  return bytes + 4 * 36 * 1024;
}

/// /steps with an empty dataset per step field, and /timing; returns the bytes a step may add
/// to the file besides its residuals: its rows, a new chunk of each small dataset (4 KiB), the
/// chunk indices (up to a 1024-entry page of each) and other metadata.
hsize_t create_step_datasets(const H5File& f, const std::vector<StepDataset>& datasets) {
  f.create_group("/steps");
  hsize_t reserve = 256 * 1024;
  for (const StepDataset& d : datasets) {
    f.create_rows("/steps/" + d.name, d.type, d.row);
    hsize_t bytes = H5Tget_size(d.type);
    for (const hsize_t n : d.row) bytes *= n;
    reserve += bytes + 36 * 1024;
  }
  f.create_group("/timing");
  f.create_text_rows("/timing/phases", kPhaseBytes);
  f.create_rows("/timing/seconds", H5Type<double>::file(), {});
  return reserve;
}

}  // namespace

ResultsFile::ResultsFile(const std::string& path, const Mesh& mesh, const VectorX& depth,
                         const RunInfo& info) {
  check_writable(path, mesh, depth, info);
  const std::filesystem::path fs_path(path);
  WriterLock lock(path, results_lock_path(path));
  const std::string staging = staging_path(fs_path);
  const std::vector<SidecarBlock> blocks = sidecar_blocks(mesh, info);
  state_ = std::make_unique<State>(State{.lock = std::move(lock),
                                         .file = H5File::create(staging, path),
                                         .X = mesh.X,
                                         .num_tets = mesh.num_tets(),
                                         .tris = mesh.tris,
                                         .info = info,
                                         .depth = depth.size() != 0});
  State& s = *state_;
  H5File& f = s.file;
  bool renamed = false;
  try {
    write_mesh(f, mesh, depth, info, blocks);
    write_run(f, info);
    write_reference(f, mesh, info);
    s.step_reserve = create_step_datasets(f, s.step_datasets()) +
                     create_restart_datasets(f, info.restart, mesh.num_nodes(), mesh.num_tets());
    f.start_swmr_write();
    f.flush();
    f.rename(path);
    renamed = true;
    for (const auto& [sidecar, dialect] : sidecar_paths(fs_path)) {
      s.sidecars.emplace_back(sidecar.string(),
                              SidecarLayout{.h5_name = fs_path.filename().string(),
                                            .dialect = dialect,
                                            .num_nodes = mesh.num_nodes(),
                                            .num_tets = mesh.num_tets(),
                                            .num_tris = mesh.num_tris(),
                                            .blocks = blocks,
                                            .depth = depth.size() != 0,
                                            .fields = info.fields},
                              SidecarStep{.row = -1, .time = 0.0, .values = {}});
    }
  } catch (const InputError& e) {
    std::error_code ignored;
    std::filesystem::remove(staging, ignored);
    if (renamed) {  // the file is in place, its sidecars are not: it says why it stays empty
      try {
        finish(false, e.what());
      } catch (const InputError&) {
      }
    }
    throw;
  }
}

ResultsFile::~ResultsFile() = default;

void ResultsFile::State::check_step(const StepRecord& step, const Points& x, const Points* v,
                                    const ElementFields* elements,
                                    const RestartRecord* restart) const {
  const H5File& f = file;
  const ResultFields& fields = info.fields;
  const std::string what = "step " + std::to_string(step.index);
  const auto expect_rows = [&](const char* name, Eigen::Index rows, Eigen::Index expected,
                               const char* of) {
    if (rows != expected)
      f.fail(what + ": " + name + " has " + std::to_string(rows) + " rows, expected " +
             std::to_string(expected) + " (" + of + ")");
  };
  const Eigen::Index tets = num_tets;
  if (step.index <= last_index)
    f.fail(what + ": steps must come in increasing order (the last one written was " +
           std::to_string(last_index) + ")");
  if (num_steps >= kMaxSteps)
    f.fail(what + ": a results file holds at most " + std::to_string(kMaxSteps) + " steps");
  expect_rows("x", x.rows(), num_nodes(), "#nodes");
  if (bool(v) != fields.velocity)
    f.fail(what +
           (fields.velocity ? ": velocities missing" : ": velocities given to a run without"));
  if (v) expect_rows("v", v->rows(), num_nodes(), "#nodes");
  expect_rows("reactions", step.reactions.rows(), Eigen::Index(info.constraint_names.size()),
              "#constraints");
  if ((fields.stress || fields.strain || fields.viscous) && !elements)
    f.fail(what + ": element fields missing");
  if (fields.viscous) expect_rows("viscous_stress", elements->viscous_stress.rows(), tets, "#tets");
  if (fields.stress) {
    expect_rows("stress", elements->stress.rows(), tets, "#tets");
    expect_rows("von_mises", elements->von_mises.rows(), tets, "#tets");
  }
  if (fields.strain) {
    expect_rows("strain", elements->strain.rows(), tets, "#tets");
    expect_rows("volume_ratio", elements->volume_ratio.rows(), tets, "#tets");
  }
  if (fields.contact) expect_rows("surface", step.surface.area.rows(), tris.rows(), "#tris");
  if (bool(restart) == info.restart.empty())
    f.fail(what +
           (restart ? ": a restart record given to a run without" : ": restart record missing"));
  if (restart && info.restart.acceleration)
    expect_rows("acceleration", restart->acceleration.rows(), num_nodes(), "#nodes");
  if (restart && info.restart.force)
    expect_rows("force", restart->force.rows(), num_nodes(), "#nodes");
  if (restart && info.restart.history_columns > 0) {
    expect_rows("history", restart->history.rows(), tets, "#tets");
    if (restart->history.cols() != info.restart.history_columns)
      f.fail(what + ": the viscoelastic history has " + std::to_string(restart->history.cols()) +
             " columns, the run declared " + std::to_string(info.restart.history_columns));
  }
  std::vector<std::string> contact_names;
  for (const InterfaceForce& c : step.contact) contact_names.push_back(c.name);
  if (contact_names != info.contact_names)
    f.fail(what + ": its contact interfaces are not those the run declared");
}

hsize_t ResultsFile::State::write_rows(const StepRecord& step, const Points& x, const Points* v,
                                       const ElementFields* elements,
                                       const RestartRecord* restart) const {
  const H5File& f = file;
  const ResultFields& fields = info.fields;
  // Every dataset of the step at row k, then the index: a reader counts the rows of
  // /steps/index, so a step is in the file once its index is. A full disk stops the run before
  // the step is begun.
  const H5File::Reservation reserved =
      f.reserve(step_reserve + step.residuals.size() * sizeof(double));
  const hsize_t k = hsize_t(num_steps);
  // The restart record goes into the slot of the step before last, marked empty (and flushed)
  // before it is overwritten and marked with the step once the step's rows are flushed: a slot
  // marked with a step holds that step's record at every moment, and the last written step's
  // slot is never the one being overwritten.
  const hsize_t slot = k % kRestartSlots;
  if (restart) {
    f.write_row("/restart/step", slot, std::int32_t(-1));
    f.flush();
    if (info.restart.acceleration)
      f.write_row("/restart/acceleration", slot, restart->acceleration);
    if (info.restart.history_columns > 0) f.write_row("/restart/history", slot, restart->history);
    if (info.restart.force) f.write_row("/restart/force", slot, restart->force);
  }
  f.write_row("/steps/load", k, step.load);
  f.write_row("/steps/settling", k, std::int32_t(step.settling));
  f.write_row("/steps/newton_iterations", k, std::int32_t(step.newton_iterations));
  f.write_row("/steps/linear_iterations", k, std::int32_t(step.linear_iterations));
  f.write_row("/steps/linear_solves", k, std::int32_t(step.linear_solves));
  f.write_row("/steps/factorizations", k, std::int32_t(step.factorizations));
  f.write_row("/steps/energy", k, step.energy);
  f.write_row("/steps/seconds", k, step.seconds);
  f.write_row("/steps/residual_count", k, std::int32_t(step.residuals.size()));
  f.write_rows("/steps/residuals", num_residuals, step.residuals.size(), H5Type<double>::memory(),
               step.residuals.data());
  f.write_row("/steps/reactions", k, step.reactions);
  f.write_row("/steps/x", k, x);
  if (fields.displacement) f.write_row("/steps/displacement", k, (x - X).eval());
  if (v) {
    f.write_row("/steps/v", k, *v);
    f.write_row("/steps/kinetic_energy", k, step.kinetic_energy);
  }
  if (!step.contact.empty()) {
    const Eigen::Index rows = Eigen::Index(step.contact.size());
    Eigen::Matrix<double, Eigen::Dynamic, 3> forces(rows, 3);
    VectorX magnitudes(rows), areas(rows);
    for (Eigen::Index c = 0; c < rows; ++c) {
      forces.row(c) = step.contact[c].force.transpose();
      magnitudes(c) = step.contact[c].magnitude;
      areas(c) = step.contact[c].area;
    }
    f.write_row("/steps/contact_area", k, step.contact_area());
    f.write_row("/steps/contact_forces", k, forces);
    f.write_row("/steps/contact_force_magnitudes", k, magnitudes);
    f.write_row("/steps/contact_areas", k, areas);
  }
  if (depth)
    f.write_row("/steps/penetration", k,
                step.penetration.value_or(std::numeric_limits<double>::quiet_NaN()));
  if (fields.stress) {
    f.write_row("/steps/stress", k, elements->stress);
    f.write_row("/steps/von_mises", k, elements->von_mises);
  }
  if (fields.strain) {
    f.write_row("/steps/strain", k, elements->strain);
    f.write_row("/steps/volume_ratio", k, elements->volume_ratio);
  }
  if (fields.viscous) {
    f.write_row("/steps/dissipated_energy", k,
                step.dissipated_energy.value_or(std::numeric_limits<double>::quiet_NaN()));
    f.write_row("/steps/viscous_stress", k, elements->viscous_stress);
  }
  if (fields.contact) {
    const SurfaceFields surface = surface_fields(tris, x, step.surface);
    f.write_row("/steps/contact_pressure", k, surface.pressure);
    f.write_row("/steps/contact_traction", k, surface.traction);
    f.write_row("/steps/contact_gap", k, surface.gap);
    f.write_row("/steps/contact_fraction", k, surface.fraction);
  }
  f.flush();
  if (restart) {
    f.write_row("/restart/step", slot, std::int32_t(step.index));
    f.flush();
  }
  f.write_row("/steps/index", k, std::int32_t(step.index));
  f.flush();
  return k;
}

void ResultsFile::append_step(const StepRecord& step, const Points& x, const Points* v,
                              const ElementFields* elements, const RestartRecord* restart) {
  State& s = *state_;
  s.check_step(step, x, v, elements, restart);
  const hsize_t k = s.write_rows(step, x, v, elements, restart);
  ++s.num_steps;
  s.last_index = step.index;
  s.num_residuals += step.residuals.size();
  // ParaView shows one state per distinct time: settling steps, all at load 1, follow at 2, 3, ...
  const double time = step.settling ? 1.0 + double(++s.settling_steps) : step.load;
  const SidecarStep entry{
      .row = Index(k),
      .time = time,
      .values = step_values(step, s.info.fields.velocity, s.info.constraint_names)};
  for (XdmfSidecar& sidecar : s.sidecars) sidecar.append(entry);
}

void ResultsFile::write_timing(const std::vector<std::pair<std::string, double>>& phases) {
  const H5File& f = state_->file;
  const H5File::Reservation reserved = f.reserve(64 * 1024);
  std::vector<std::string> names;
  VectorX seconds(Eigen::Index(phases.size()));
  for (size_t k = 0; k < phases.size(); ++k) {
    names.push_back(phases[k].first);
    seconds(Eigen::Index(k)) = phases[k].second;
  }
  f.write_text_rows("/timing/phases", names);
  f.set_rows("/timing/seconds", phases.size());
  f.write_rows("/timing/seconds", 0, phases.size(), H5Type<double>::memory(), seconds.data());
  f.flush();
}

void ResultsFile::finish(bool success, const std::string& message) {
  const H5File& f = state_->file;
  f.write_text("/run/message", message);
  f.write_text("/run/status", success ? "completed" : "failed");
  f.flush();
}

ResultsSummary read_results_summary(const std::string& path) {
  const H5File file = open_results(path);
  ResultsSummary out;
  out.num_nodes = checked_rows(file, "/mesh/X", H5T_FLOAT, 3, "#nodes x 3");
  out.num_tets = checked_rows(file, "/mesh/tets", H5T_INTEGER, 4, "#tets x 4");
  out.num_tris = checked_rows(file, "/mesh/tris", H5T_INTEGER, 3, "#triangles x 3");
  checked_dims(file, "/mesh/body_names", H5T_STRING, {kAny}, "one name per body");
  out.body_names = file.read_strings("/mesh/body_names");
  std::vector<std::string> run = file.string_attributes("/run", {"analysis", "version"});
  out.analysis = std::move(run[0]);
  out.version = std::move(run[1]);
  out.status = one_text(file, "/run/status");
  if (out.status != "running" && out.status != "completed" && out.status != "failed")
    file.fail("/run/status is neither running, completed nor failed");
  out.message = one_text(file, "/run/message");
  out.threads = file.attribute<int>("/run", "threads");
  if (out.threads < 1) file.fail("/run attribute threads is " + std::to_string(out.threads));
  const hsize_t n = num_steps(file);
  out.num_steps = static_cast<Index>(n);
  for (const auto& [name, total] :
       {std::pair<const char*, long*>{"/steps/newton_iterations", &out.total_newton_iterations},
        std::pair<const char*, long*>{"/steps/linear_iterations", &out.total_linear_iterations}}) {
    checked_dims(file, name, H5T_INTEGER, {kAny}, "one value per step");
    for (const double k : file.read_rows(name, 0, n))
      *total += whole_number(file, name, k, 0, std::numeric_limits<std::int32_t>::max());
  }
  if (n > 0) {
    checked_dims(file, "/steps/load", H5T_FLOAT, {kAny}, "one value per step");
    out.last_load = finite_number(file, "/steps/load", file.read_rows("/steps/load", n - 1, 1)[0],
                                  "the last step's");
  }
  checked_dims(file, "/timing/phases", H5T_STRING, {kAny}, "one name per phase");
  const std::vector<std::string> phases = file.read_texts("/timing/phases");
  const hsize_t rows =
      checked_dims(file, "/timing/seconds", H5T_FLOAT, {kAny}, "one value per phase")[0];
  const std::vector<double> seconds = file.read_rows("/timing/seconds", 0, rows);
  for (size_t k = 0; k < std::min(phases.size(), seconds.size()); ++k) {
    if (!(finite_number(file, "/timing/seconds", seconds[k], "phase " + std::to_string(k)) >= 0))
      file.fail("/timing/seconds holds a negative time (phase " + std::to_string(k) + ")");
    out.timing.emplace_back(phases[k], seconds[k]);
  }
  return out;
}

Eigen::MatrixXd read_step_dataset(const std::string& path, Index step, const std::string& name) {
  const H5File file = open_results(path);
  const std::vector<Index> indices = step_indices(file);
  const hsize_t row = step_row(file, indices, step);
  const std::string dataset = "/steps/" + name;
  if (name == "index" || !file.exists(dataset)) file.fail("has no dataset " + dataset);
  if (name == "residuals") {
    // Step k's residuals follow those of the steps before, residual_count[k] of them.
    const char* counts_name = "/steps/residual_count";
    checked_dims(file, counts_name, H5T_INTEGER, {kAny}, "one value per step");
    checked_dims(file, dataset, H5T_FLOAT, {kAny}, "one list of all residuals");
    const std::vector<double> counts = file.read_rows(counts_name, 0, row + 1);
    hsize_t first = 0, count = 0;
    for (hsize_t k = 0; k <= row; ++k) {
      first += count;
      count = hsize_t(
          whole_number(file, counts_name, counts[k], 0, std::numeric_limits<std::int32_t>::max()));
    }
    const std::vector<double> values = file.read_rows(dataset, first, count);
    return Eigen::Map<const VectorX>(values.data(), Eigen::Index(values.size()));
  }
  const H5T_class_t type = file.type_class(dataset);
  if (type != H5T_INTEGER && type != H5T_FLOAT)
    file.fail(dataset + " holds " + class_text(type) + ", not numbers");
  const std::vector<hsize_t> dims = file.dims(dataset);
  const auto too_large = [](hsize_t n) { return n > hsize_t(std::numeric_limits<Index>::max()); };
  if (dims.empty() || dims.size() > 3 || std::any_of(dims.begin() + 1, dims.end(), too_large))
    file.fail(dataset + " has shape " + shape_text(dims) +
              ", not #steps (x rows (x columns)): a series of scalars, vectors or matrices");
  const std::vector<double> values = file.read_rows(dataset, row, 1);
  // read_rows read as many values as the rows and columns hold (it checked their product).
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), dims.size() > 1 ? Eigen::Index(dims[1]) : 1,
      dims.size() > 2 ? Eigen::Index(dims[2]) : 1);
}

Points read_step_positions(const std::string& path, Index step) {
  return read_step_dataset(path, step, "x");
}

StepState read_step_state(const std::string& path, Index step) {
  const H5File file = open_results(path);
  const std::vector<Index> indices = step_indices(file);
  if (indices.empty()) file.fail("has no completed step to restart from");
  StepState out;
  out.index = step < 0 ? indices.back() : step;
  const hsize_t row = step_row(file, indices, out.index);
  const std::string of_step = "step " + std::to_string(out.index);
  checked_dims(file, "/steps/load", H5T_FLOAT, {kAny}, "one value per step");
  out.load = finite_number(file, "/steps/load", file.read_rows("/steps/load", row, 1)[0], of_step);
  const Index nodes = checked_rows(file, "/mesh/X", H5T_FLOAT, 3, "#nodes x 3");
  const auto node_rows = [&](const std::string& name) -> Points {
    checked_dims(file, name, H5T_FLOAT, {kAny, hsize_t(nodes), 3},
                 "#steps x " + std::to_string(nodes) + " x 3 (the nodes of /mesh/X)");
    const std::vector<double> values = file.read_rows(name, row, 1);
    for (size_t k = 0; k < values.size(); ++k)
      finite_number(file, name, values[k], of_step + ", node " + std::to_string(k / 3));
    return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(
        values.data(), nodes, 3);
  };
  out.x = node_rows("/steps/x");
  if (file.exists("/steps/v")) out.v = node_rows("/steps/v");
  return out;
}

namespace {

/// Row `slot` of dataset `name` of #slots x `nodes_or_tets` x `columns` finite doubles (`rows`:
/// what the middle dimension counts, for messages), as a matrix; throws naming the file and the
/// dataset when it is not one.
Eigen::MatrixXd restart_rows(const H5File& file, const std::string& name, hsize_t slot, Index rows,
                             Index columns, const std::string& rows_text, Index step) {
  checked_dims(file, name, H5T_FLOAT, {kAny, hsize_t(rows), hsize_t(columns)},
               "#slots x " + std::to_string(rows) + " x " + std::to_string(columns) + " (" +
                   rows_text + ")");
  const std::vector<double> values = file.read_rows(name, slot, 1);
  for (size_t k = 0; k < values.size(); ++k)
    finite_number(file, name, values[k],
                  "step " + std::to_string(step) + ", row " + std::to_string(k / size_t(columns)));
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), rows, columns);
}

}  // namespace

RestartRecord read_restart_record(const std::string& path, Index step,
                                  const RestartLayout& layout) {
  const H5File file = open_results(path);
  step_row(file, step_indices(file), step);
  RestartRecord out;
  const bool history = file.exists("/restart/history");
  if (layout.history_columns == 0 && history)
    file.fail(
        "holds a viscoelastic history (/restart/history), and the scene has no "
        "viscoelastic material: it was written for another scene");
  if (layout.empty()) return out;
  if (!file.exists("/restart"))
    file.fail("has no restart record (/restart): " +
              std::string(layout.acceleration ? "the scene's integrator carries an acceleration"
                                              : "the scene has viscoelastic materials") +
              ", which the run that wrote it did not");
  checked_dims(file, "/restart/step", H5T_INTEGER, {kRestartSlots}, "one step per slot (2)");
  const std::vector<double> marks = file.read_rows("/restart/step", 0, kRestartSlots);
  std::optional<hsize_t> slot;
  std::string held;
  for (hsize_t k = 0; k < kRestartSlots; ++k) {
    const long long mark =
        whole_number(file, "/restart/step", marks[k], -1, std::numeric_limits<std::int32_t>::max());
    if (mark == step) slot = k;
    if (mark >= 0) held += (held.empty() ? "" : ", ") + std::to_string(mark);
  }
  if (!slot)
    file.fail("/restart/step: no restart record of step " + std::to_string(step) +
              " (records of steps: " + (held.empty() ? "none" : held) +
              "; a run keeps those of its last two written steps)");
  const Index nodes = checked_rows(file, "/mesh/X", H5T_FLOAT, 3, "#nodes x 3");
  const Index tets = checked_rows(file, "/mesh/tets", H5T_INTEGER, 4, "#tets x 4");
  if (layout.acceleration) {
    if (!file.exists("/restart/acceleration"))
      file.fail(
          "has no dataset /restart/acceleration: the run that wrote it carried no "
          "acceleration (another integrator than newmark or generalized_alpha)");
    out.acceleration =
        restart_rows(file, "/restart/acceleration", *slot, nodes, 3, "the nodes of /mesh/X", step);
  }
  if (layout.force) {
    if (!file.exists("/restart/force"))
      file.fail(
          "has no dataset /restart/force: the run that wrote it carried no force (another "
          "integrator than symplectic_euler)");
    out.force = restart_rows(file, "/restart/force", *slot, nodes, 3, "the nodes of /mesh/X", step);
  }
  if (layout.history_columns > 0) {
    if (!history)
      file.fail(
          "has no dataset /restart/history: the run that wrote it had no viscoelastic "
          "material in time, the scene has");
    out.history = restart_rows(file, "/restart/history", *slot, tets, layout.history_columns,
                               "the tets of /mesh/tets, the columns of the scene's viscoelastic "
                               "history",
                               step);
  }
  return out;
}

void check_results_mesh(const std::string& path, const Mesh& mesh) {
  const H5File file = open_results(path);
  const Index nodes = checked_rows(file, "/mesh/X", H5T_FLOAT, 3, "#nodes x 3");
  const Index tets = checked_rows(file, "/mesh/tets", H5T_INTEGER, 4, "#tets x 4");
  if (nodes != mesh.num_nodes() || tets != mesh.num_tets())
    file.fail("was written for another mesh: /mesh/X and /mesh/tets hold " + std::to_string(nodes) +
              " nodes and " + std::to_string(tets) + " tets, the mesh " +
              std::to_string(mesh.num_nodes()) + " and " + std::to_string(mesh.num_tets()));
  const std::vector<double> tet_nodes = file.read_rows("/mesh/tets", 0, hsize_t(tets));
  for (Index t = 0; t < tets; ++t)
    for (int c = 0; c < 4; ++c)
      if (tet_nodes[size_t(4 * t + c)] != double(mesh.tets(t, c)))
        file.fail("was written for another mesh: /mesh/tets row " + std::to_string(t) +
                  " is not the mesh's tet " + std::to_string(t));
  // The same scene read or generated by another build (with or without fused multiply-adds) may
  // place a node a few units in the last place apart; 1e-9 of the mesh's size is far above that
  // and far below any difference between two meshes that a scene means.
  const std::vector<double> X = file.read_rows("/mesh/X", 0, hsize_t(nodes));
  const double size =
      nodes > 0 ? (mesh.X.colwise().maxCoeff() - mesh.X.colwise().minCoeff()).norm() : 0.0;
  for (Index i = 0; i < nodes; ++i) {
    const Vec3 in_file(X[size_t(3 * i)], X[size_t(3 * i + 1)], X[size_t(3 * i + 2)]);
    if (!((in_file - mesh.X.row(i).transpose()).norm() <= 1e-9 * size))
      file.fail("was written for another mesh: /mesh/X row " + std::to_string(i) +
                " is not the position of the mesh's node " + std::to_string(i));
  }
}

}  // namespace depthfem
