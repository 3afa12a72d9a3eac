#include "core/results_file.hpp"

#include <cstdio>
#include <filesystem>

#include "core/error.hpp"
#include "core/hdf5_file.hpp"
#include "core/text_parsing.hpp"
#include "core/xdmf_writer.hpp"

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

}  // namespace

struct ResultsFile::State {
  H5File file;
  std::string xmf_path;  ///< the sidecar
  std::string h5_name;   ///< file name of the results file, as the sidecar refers to it
  Index num_nodes = 0, num_tets = 0, num_constraints = 0;
  std::vector<SidecarStep> steps;
  std::vector<std::string> contact_names;  ///< of the first step; later steps must match

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

void ResultsFile::append_step(const StepRecord& step, const Points& x, const Points* v) {
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
  expect_rows("x", x.rows(), s.num_nodes, "#nodes");
  if (v) expect_rows("v", v->rows(), s.num_nodes, "#nodes");
  expect_rows("reactions", step.reactions.rows(), s.num_constraints, "#constraints");
  std::vector<std::string> contact_names;
  for (const InterfaceForce& c : step.contact) contact_names.push_back(c.name);
  if (!s.steps.empty() && contact_names != s.contact_names)
    f.fail(group + ": the contact interfaces differ from those of the first step");
  if (f.exists(group)) f.fail(group + " was already written");

  if (s.steps.empty() && !contact_names.empty()) {
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
    f.write_array(group + "/contact_forces", forces);
    f.write_array(group + "/contact_force_magnitudes", magnitudes);
    f.write_array(group + "/contact_areas", areas);
  }
  f.flush();

  s.steps.push_back({step_name(step.index), group, step.load, v != nullptr});
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
