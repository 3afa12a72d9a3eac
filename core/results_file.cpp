#include "core/results_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <utility>

#include "core/error.hpp"
#include "core/hdf5_file.hpp"

namespace depthfem {
namespace {

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

/// Per-node and per-tet datasets a state group may hold, by the rows they have.
constexpr const char* kNodeDatasets[] = {"x", "displacement", "v"};
constexpr const char* kTetDatasets[] = {"stress", "von_mises", "strain", "volume_ratio"};

/// The sidecar's blocks: one per body, named after it and its materials, except that a body with
/// several element regions has one per region, named "BODY/REGION (material)", with the body's
/// nodes and the region's tets. A single block is the whole mesh (it uses the scene's datasets);
/// several have their own views.
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
      blocks.push_back({named(body.name, info.body_materials, b), "", body.num_nodes, body.num_tets,
                        body.first_node, body.first_tet});
    } else {
      for (size_t r = 0; r < body.regions.size(); ++r) {
        const Region& here = body.regions[r];
        blocks.push_back({named(body.name + "/" + here.name, info.region_materials, region + r), "",
                          body.num_nodes, here.num_tets, body.first_node, here.first_tet});
      }
    }
    region += body.regions.size();
  }
  if (blocks.size() > 1)
    for (size_t k = 0; k < blocks.size(); ++k) blocks[k].path = "blocks/" + std::to_string(k) + "/";
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
                             {"residual", {step.residuals.empty() ? 0.0 : step.residuals.back()}},
                             {"energy", {step.energy}}};
  if (velocity) out.push_back({"kinetic_energy", {step.kinetic_energy}});
  for (size_t k = 0; k < constraint_names.size(); ++k) {
    const auto r = step.reactions.row(Eigen::Index(k));
    out.push_back({"reaction " + constraint_names[k], {r(0), r(1), r(2)}});
  }
  if (!step.contact.empty()) out.push_back({"contact_area", {step.contact_area()}});
  if (step.penetration) out.push_back({"penetration", {*step.penetration}});
  for (const InterfaceForce& c : step.contact) {
    out.push_back({"contact_force " + c.name, {c.force(0), c.force(1), c.force(2)}});
    out.push_back({"contact_force_magnitude " + c.name, {c.magnitude}});
    out.push_back({"contact_area " + c.name, {c.area}});
  }
  return out;
}

}  // namespace

// The writer's lock on a results file: the hidden file ".NAME.lock" beside it holds an
// exclusive flock and the writer's process id while the run writes, so that a second run with
// the same --out is refused before it truncates the file. Removed with the writer.
class WriterLock {
 public:
  WriterLock(const std::string& path, const std::filesystem::path& lock_path)
      : lock_path_(lock_path.string()) {
    fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw InputError(located(path, 0, "cannot create the lock file " + lock_path_));
    if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      char pid[32] = {};
      const ssize_t n = pread(fd_, pid, sizeof pid - 1, 0);
      ::close(fd_);
      throw InputError(located(path, 0,
                               "is being written by another depthfem run (process " +
                                   std::string(pid, n > 0 ? size_t(n) : 0) +
                                   "); wait for it to end or choose another --out"));
    }
    const std::string pid = std::to_string(getpid());
    if (ftruncate(fd_, 0) != 0 || pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
      ::close(fd_);
      throw InputError(located(path, 0, "cannot write the lock file " + lock_path_));
    }
  }
  WriterLock(WriterLock&& other) noexcept
      : lock_path_(std::move(other.lock_path_)), fd_(std::exchange(other.fd_, -1)) {}
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;
  WriterLock& operator=(WriterLock&&) = delete;
  ~WriterLock() {
    if (fd_ < 0) return;
    std::error_code ignored;
    std::filesystem::remove(lock_path_, ignored);  // before the lock is released
    ::close(fd_);
  }

 private:
  std::string lock_path_;
  int fd_ = -1;
};

struct ResultsFile::State {
  WriterLock lock;  // taken before the file is created (truncated)
  H5File file;
  Points X;  ///< reference positions, for displacements
  Index num_tets = 0;
  TriIndices tris;
  RunInfo info;
  std::vector<SidecarBlock> blocks;
  std::optional<XdmfSidecar> sidecar;
  Index num_steps = 0;
  Index settling_steps = 0;
  std::vector<std::string> contact_names;  ///< of the first step; later steps must match

  Index num_nodes() const { return static_cast<Index>(X.rows()); }

  /// Row views blocks/<b>/NAME of every node and tet dataset of `group`, for the sidecar.
  void write_block_views(const std::string& group) const {
    if (blocks.size() < 2) return;
    file.create_group(group + "/blocks");
    for (size_t b = 0; b < blocks.size(); ++b) {
      const std::string here = group + "/" + blocks[b].path;
      file.create_group(here.substr(0, here.size() - 1));
      const SidecarBlock& block = blocks[b];
      for (const char* name : kNodeDatasets)
        if (file.exists(group + "/" + name))
          file.create_row_view(here + name, group + "/" + name, hsize_t(block.first_node),
                               hsize_t(block.num_nodes));
      for (const char* name : kTetDatasets)
        if (file.exists(group + "/" + name))
          file.create_row_view(here + name, group + "/" + name, hsize_t(block.first_tet),
                               hsize_t(block.num_tets));
    }
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
  if (info.fields.velocity && info.initial_velocity.rows() != mesh.num_nodes())
    throw InputError(located(path, 0,
                             "the initial velocity has " +
                                 std::to_string(info.initial_velocity.rows()) + " rows, the mesh " +
                                 std::to_string(mesh.num_nodes()) + " nodes"));
  WriterLock lock(path, fs_path.parent_path() / ("." + fs_path.filename().string() + ".lock"));
  state_ = std::make_unique<State>(State{std::move(lock),
                                         H5File::create(path),
                                         mesh.X,
                                         mesh.num_tets(),
                                         mesh.tris,
                                         info,
                                         sidecar_blocks(mesh, info),
                                         {},
                                         0,
                                         0,
                                         {}});
  State& s = *state_;
  const H5File& f = s.file;
  const ResultFields& fields = info.fields;

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
    for (const auto& [name, nodes] : mesh.node_sets) {
      std::string object = name;  // '/' would open a subgroup
      std::ranges::replace(object, '/', '_');
      f.write_array("/mesh/node_sets/" + object,
                    Eigen::Map<const IndexVector>(nodes.data(), Eigen::Index(nodes.size())));
    }
  }
  if (s.blocks.size() > 1) {
    f.create_group("/mesh/blocks");
    for (const SidecarBlock& block : s.blocks) {
      const std::string here = "/mesh/" + block.path;
      f.create_group(here.substr(0, here.size() - 1));
      f.set_string_attribute(here.substr(0, here.size() - 1), "name", block.name);
      const TetIndices local =
          (mesh.tets.middleRows(block.first_tet, block.num_tets).array() - block.first_node)
              .matrix();
      f.write_array(here + "tets", local);
      if (depth.size() != 0)
        f.create_row_view(here + "depth", "/mesh/depth", hsize_t(block.first_node),
                          hsize_t(block.num_nodes));
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

  // The reference state: what the first step starts from.
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
  if (fields.contact) {
    for (const char* name : {"contact_pressure", "contact_gap", "contact_fraction"})
      f.create_zeros(std::string("/reference/") + name, {tris});
    f.create_zeros("/reference/contact_traction", {tris, 3});
  }
  s.write_block_views("/reference");

  f.create_group("/steps");
  f.flush();
  s.sidecar.emplace(std::filesystem::path(fs_path).replace_extension(".xmf").string(),
                    SidecarLayout{fs_path.filename().string(), mesh.num_nodes(), mesh.num_tris(),
                                  s.blocks, depth.size() != 0, fields},
                    SidecarStep{"/reference", 0.0, {}});
}

ResultsFile::~ResultsFile() = default;

void ResultsFile::append_step(const StepRecord& step, const Points& x, const Points* v,
                              const ElementFields* elements) {
  State& s = *state_;
  const H5File& f = s.file;
  const ResultFields& fields = s.info.fields;
  const std::string group = step_group(step.index);
  const auto expect_rows = [&](const char* name, Eigen::Index rows, Eigen::Index expected,
                               const char* of) {
    if (rows != expected)
      f.fail(group + ": " + name + " has " + std::to_string(rows) + " rows, expected " +
             std::to_string(expected) + " (" + of + ")");
  };
  const Eigen::Index num_tets = s.num_tets;
  if (step.index < 0 || step.index > kMaxStepIndex)
    f.fail("step index " + std::to_string(step.index) + " is outside 0.." +
           std::to_string(kMaxStepIndex));
  expect_rows("x", x.rows(), s.num_nodes(), "#nodes");
  if (bool(v) != fields.velocity)
    f.fail(group +
           (fields.velocity ? ": velocities missing" : ": velocities given to a run without"));
  if (v) expect_rows("v", v->rows(), s.num_nodes(), "#nodes");
  expect_rows("reactions", step.reactions.rows(), Eigen::Index(s.info.constraint_names.size()),
              "#constraints");
  if ((fields.stress || fields.strain) && !elements) f.fail(group + ": element fields missing");
  if (fields.stress) {
    expect_rows("stress", elements->stress.rows(), num_tets, "#tets");
    expect_rows("von_mises", elements->von_mises.rows(), num_tets, "#tets");
  }
  if (fields.strain) {
    expect_rows("strain", elements->strain.rows(), num_tets, "#tets");
    expect_rows("volume_ratio", elements->volume_ratio.rows(), num_tets, "#tets");
  }
  if (fields.contact) expect_rows("surface", step.surface.area.rows(), s.tris.rows(), "#tris");
  std::vector<std::string> contact_names;
  for (const InterfaceForce& c : step.contact) contact_names.push_back(c.name);
  if (s.num_steps > 0 && contact_names != s.contact_names)
    f.fail(group + ": the contact interfaces differ from those of the first step");
  if (f.exists(group)) f.fail(group + " was already written");

  if (s.num_steps == 0 && !contact_names.empty()) {
    f.write_strings("/run/contact_names", contact_names);
    s.contact_names = contact_names;
  }
  f.create_group(group);
  f.set_attribute(group, "index", step.index);
  f.set_attribute(group, "load", step.load);
  f.set_attribute(group, "settling", std::int32_t(step.settling));
  f.set_attribute(group, "newton_iterations", step.newton_iterations);
  f.set_attribute(group, "linear_iterations", step.linear_iterations);
  f.set_attribute(group, "energy", step.energy);
  if (v) f.set_attribute(group, "kinetic_energy", step.kinetic_energy);
  f.set_attribute(group, "seconds", step.seconds);
  f.write_array(group + "/x", x);
  if (fields.displacement) f.write_array(group + "/displacement", (x - s.X).eval());
  if (v) f.write_array(group + "/v", *v);
  f.write_array(
      group + "/residuals",
      Eigen::Map<const VectorX>(step.residuals.data(), Eigen::Index(step.residuals.size())));
  f.write_array(group + "/reactions", step.reactions);
  if (!step.contact.empty()) {
    const Eigen::Index rows = Eigen::Index(step.contact.size());
    Eigen::Matrix<double, Eigen::Dynamic, 3> forces(rows, 3);
    VectorX magnitudes(rows), areas(rows);
    for (Eigen::Index k = 0; k < rows; ++k) {
      forces.row(k) = step.contact[k].force.transpose();
      magnitudes(k) = step.contact[k].magnitude;
      areas(k) = step.contact[k].area;
    }
    f.set_attribute(group, "contact_area", step.contact_area());
    if (step.penetration) f.set_attribute(group, "penetration", *step.penetration);
    f.write_array(group + "/contact_forces", forces);
    f.write_array(group + "/contact_force_magnitudes", magnitudes);
    f.write_array(group + "/contact_areas", areas);
  }
  if (fields.stress) {
    f.write_array(group + "/stress", elements->stress);
    f.write_array(group + "/von_mises", elements->von_mises);
  }
  if (fields.strain) {
    f.write_array(group + "/strain", elements->strain);
    f.write_array(group + "/volume_ratio", elements->volume_ratio);
  }
  if (fields.contact) {
    const SurfaceFields surface = surface_fields(s.tris, x, step.surface);
    f.write_array(group + "/contact_pressure", surface.pressure);
    f.write_array(group + "/contact_traction", surface.traction);
    f.write_array(group + "/contact_gap", surface.gap);
    f.write_array(group + "/contact_fraction", surface.fraction);
  }
  s.write_block_views(group);
  f.flush();
  ++s.num_steps;
  // ParaView shows one state per distinct time: settling steps, all at load 1, follow at 2, 3, ...
  const double time = step.settling ? 1.0 + double(++s.settling_steps) : step.load;
  s.sidecar->append({group, time, step_values(step, fields.velocity, s.info.constraint_names)});
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

Eigen::MatrixXd read_step_dataset(const std::string& path, Index step, const std::string& name) {
  const H5File file = open_results(path);
  const std::string group = step_group(step);
  if (!file.exists(group)) file.fail("has no step " + std::to_string(step));
  const std::string dataset = group + "/" + name;
  if (!file.exists(dataset)) file.fail("has no dataset " + dataset);
  const std::vector<hsize_t> dims = file.dims(dataset);
  if (dims.empty() || dims.size() > 2) file.fail(dataset + " is not a 1D or 2D dataset");
  const std::vector<double> values = file.read_doubles(dataset);
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), Eigen::Index(dims[0]), dims.size() == 2 ? Eigen::Index(dims[1]) : 1);
}

Points read_step_positions(const std::string& path, Index step) {
  const Eigen::MatrixXd x = read_step_dataset(path, step, "x");
  if (x.cols() != 3) throw InputError(located(path, 0, step_group(step) + "/x is not #nodes x 3"));
  return x;
}

StepState read_step_state(const std::string& path, Index step) {
  StepState out;
  {
    const H5File file = open_results(path);
    const std::vector<std::string> steps =
        file.exists("/steps") ? file.link_names("/steps") : std::vector<std::string>();
    if (steps.empty()) file.fail("has no completed step to restart from");
    out.index = step < 0 ? std::stoll(steps.back()) : step;
    const std::string group = step_group(out.index);
    if (!file.exists(group))
      file.fail("has no step " + std::to_string(out.index) + " (steps " +
                std::to_string(std::stoll(steps.front())) + " to " +
                std::to_string(std::stoll(steps.back())) + ")");
    out.load = file.attribute<double>(group, "load");
  }
  out.x = read_step_positions(path, out.index);
  return out;
}

}  // namespace depthfem
