// Results files: exact round trip of mesh, run metadata, the reference state, steps, fields and
// timing through the HDF5 C API; per-body and per-region views; completed steps surviving a killed
// writer; the XDMF sidecar's structure (every dataset it names exists with the dimensions it
// states) and its step-by-step growth; errors naming the file.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/mesh.hpp"
#include "core/mesh_generators.hpp"
#include "core/results_file.hpp"

namespace depthfem {
namespace {

namespace fs = std::filesystem;

// Reads through the HDF5 C API directly, so that the writer is not checked by its own reader.
// Failures show as empty or zero values, which the expectations then reject. Opens without file
// locks like depthfem does: HDF5 refuses to open a file twice with different locking settings.
class RawFile {
 public:
  explicit RawFile(const fs::path& path) {
    const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(access, false, true);
    id_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, access);
    H5Pclose(access);
  }
  ~RawFile() {
    if (id_ >= 0) H5Fclose(id_);
  }
  RawFile(const RawFile&) = delete;
  RawFile& operator=(const RawFile&) = delete;

  bool has(const char* name) const { return H5Lexists(id_, name, H5P_DEFAULT) > 0; }
  bool has(const std::string& name) const { return has(name.c_str()); }

  // Whether dataset `name` is a virtual dataset (a view holding no data of its own), and the
  // bytes of data it stores.
  bool is_view(const std::string& name) const {
    const hid_t set = H5Dopen2(id_, name.c_str(), H5P_DEFAULT), plist = H5Dget_create_plist(set);
    const bool view = H5Pget_layout(plist) == H5D_VIRTUAL;
    H5Pclose(plist);
    H5Dclose(set);
    return view;
  }
  hsize_t storage(const std::string& name) const {
    const hid_t set = H5Dopen2(id_, name.c_str(), H5P_DEFAULT);
    const hsize_t bytes = H5Dget_storage_size(set);
    H5Dclose(set);
    return bytes;
  }
  std::vector<double> doubles(const std::string& name) const {
    std::vector<hsize_t> dims;
    return values<double>(name, H5T_NATIVE_DOUBLE, dims);
  }
  std::vector<hsize_t> dims(const std::string& name) const {
    std::vector<hsize_t> dims;
    values<double>(name, H5T_NATIVE_DOUBLE, dims);
    return dims;
  }
  bool has_attribute(const std::string& object, const char* name) const {
    return H5Aexists_by_name(id_, object.c_str(), name, H5P_DEFAULT) > 0;
  }

  // All values, row-major, read as `type`; `dims` receives the dataset's dimensions.
  template <class T>
  std::vector<T> values(const std::string& name, hid_t type, std::vector<hsize_t>& dims) const {
    const hid_t set = H5Dopen2(id_, name.c_str(), H5P_DEFAULT), space = H5Dget_space(set);
    dims.assign(std::max(H5Sget_simple_extent_ndims(space), 0), 0);
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    std::vector<T> out(std::max<hssize_t>(H5Sget_simple_extent_npoints(space), 0));
    if (!out.empty()) H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
    H5Sclose(space);
    H5Dclose(set);
    return out;
  }

  template <class T>
  T attribute(const std::string& object, const char* name, hid_t type) const {
    T value{};
    const hid_t attr = H5Aopen_by_name(id_, object.c_str(), name, H5P_DEFAULT, H5P_DEFAULT);
    H5Aread(attr, type, &value);
    H5Aclose(attr);
    return value;
  }

  // A scalar string attribute (variable length) or every string of a 1D string dataset.
  std::string string_attribute(const std::string& object, const char* name) const {
    const hid_t attr = H5Aopen_by_name(id_, object.c_str(), name, H5P_DEFAULT, H5P_DEFAULT);
    const hid_t type = H5Aget_type(attr);
    char* value = nullptr;
    const bool ok = H5Tis_variable_str(type) > 0 && H5Aread(attr, type, &value) >= 0;
    std::string out = ok && value ? value : "<not a variable-length string>";
    H5free_memory(value);
    H5Tclose(type);
    H5Aclose(attr);
    return out;
  }
  std::vector<std::string> strings(const char* name) const {
    const hid_t set = H5Dopen2(id_, name, H5P_DEFAULT), space = H5Dget_space(set);
    const hid_t type = H5Dget_type(set);
    std::vector<char*> raw(std::max<hssize_t>(H5Sget_simple_extent_npoints(space), 0), nullptr);
    if (!raw.empty()) H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data());
    std::vector<std::string> out;
    for (char* value : raw) {
      out.emplace_back(value ? value : "<null>");
      H5free_memory(value);
    }
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(set);
    return out;
  }

 private:
  hid_t id_;
};

// 2 x 2 x 3 nodes, 12 tets, one body "block"; depth = distance below the top face z = 0.7.
struct Fixture {
  Mesh mesh = single_body_mesh(
      box_mesh({Vec3(0.1, -0.2, 0.3), Vec3(0.4, 0.3, 0.7), Eigen::Vector3i(1, 1, 2)}), "block");
  VectorX depth = (0.7 - mesh.X.col(2).array()).matrix();
  RunInfo info{R"({"name": "squeeze", "steps": 3})",
               "0.1.0",
               "static",
               2,
               {"bottom", "top"},
               {"mooney_rivlin"},
               {},
               {},
               {}};
};

// Two bodies: "left" (12 tets) and "right" (a 2 x 1 x 1-cell box, 12 tets, 18 nodes).
Mesh two_bodies() {
  Mesh mesh;
  mesh.add_body("left", box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 1), Eigen::Vector3i(1, 1, 2)}));
  mesh.add_body("right", box_mesh({Vec3(2, 0, 0), Vec3(4, 1, 1), Eigen::Vector3i(2, 1, 1)}));
  return mesh;
}

// Step k: positions X scaled about the origin by 1 + k / 7 (not exactly representable).
Points positions(const Mesh& mesh, int k) {
  return mesh.X * (1.0 + k / 7.0);
}

// Step k's record; two contact interfaces whose values depend on k.
StepRecord step_record(int k) {
  StepRecord s;
  s.index = k;
  s.load = k / 3.0;
  s.newton_iterations = 2 + k;
  s.linear_iterations = 10 * k + 1;
  s.energy = 0.5 * k;
  s.seconds = 0.01 * k;
  for (int i = 0; i < s.newton_iterations; ++i) s.residuals.push_back(std::pow(10.0, -2.0 * i) / k);
  s.reactions.resize(2, 3);
  s.reactions << 1.0 / k, 2, 3,  //
      -1.0 / k, -2, -3;
  s.contact = {{"block/ball", Vec3(0.5 * k, -1, 2), 3.0 * k, 0.01 * k},
               {"obstacle floor", Vec3(0, 0, k), 4.0, 0.02}};
  return s;
}

// Element fields whose every value is distinct: value = k + (row * columns + column) / 1000.
ElementFields element_values(Index tets, int k) {
  ElementFields e;
  e.stress.resize(tets, 6);
  e.strain.resize(tets, 6);
  e.von_mises.resize(tets);
  e.volume_ratio.resize(tets);
  for (Index t = 0; t < tets; ++t) {
    for (int c = 0; c < 6; ++c) {
      e.stress(t, c) = k + (6 * t + c) / 1000.0;
      e.strain(t, c) = -k - (6 * t + c) / 1000.0;
    }
    e.von_mises(t) = k + t / 7.0;
    e.volume_ratio(t) = 1 + t / 9.0;
  }
  return e;
}

// Writes a results file of `mesh` without constraints and with one step: positions(mesh, 1) and
// element_values(#tets, 1), which it returns.
ElementFields write_one_step(const fs::path& path, const Mesh& mesh, const RunInfo& info) {
  const ElementFields elements = element_values(mesh.num_tets(), 1);
  StepRecord step = step_record(1);
  step.reactions.resize(0, 3);
  ResultsFile file(path, mesh, VectorX(), info);
  file.append_step(step, positions(mesh, 1), nullptr, &elements);
  return elements;
}

// Row-major values of a matrix, as the file stores them.
template <class Derived>
std::vector<double> row_major(const Eigen::MatrixBase<Derived>& m) {
  std::vector<double> out;
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out.push_back(double(m(r, c)));
  return out;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class ResultsFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("depthfem_results_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
  Fixture f_;
};

TEST_F(ResultsFileTest, RoundTripOfMeshRunStepsAndTiming) {
  const fs::path path = dir_ / "run.h5";
  std::vector<Points> x;
  for (int k = 1; k <= 3; ++k) x.push_back(positions(f_.mesh, k));
  {
    ResultsFile file(path, f_.mesh, f_.depth, f_.info);
    for (int k = 1; k <= 3; ++k) {
      file.append_step(step_record(k), x[k - 1], nullptr);
      if (k == 1) {  // readable while the writer is open
        const ResultsSummary during = read_results_summary(path);
        EXPECT_EQ(during.status, "running");
        EXPECT_EQ(during.num_steps, 1);
      }
    }
    file.write_timing({{"solve", 9.0}, {"assembly", 1.0}});
    file.write_timing({{"solve", 2.5}, {"assembly", 1.5}, {"contact", 0.25}});  // replaces
    file.finish(true, "");
  }

  const RawFile raw(path);
  std::vector<hsize_t> dims;
  const std::vector<double> X = raw.values<double>("/mesh/X", H5T_NATIVE_DOUBLE, dims);
  ASSERT_EQ(dims, std::vector<hsize_t>({12, 3}));
  EXPECT_EQ(X, row_major(f_.mesh.X));  // row-major in the file, column-major in memory
  const std::vector<int> tets = raw.values<int>("/mesh/tets", H5T_NATIVE_INT, dims);
  ASSERT_EQ(dims, std::vector<hsize_t>({12, 4}));
  for (Index t = 0; t < 12; ++t)
    for (int c = 0; c < 4; ++c) EXPECT_EQ(tets[4 * t + c], f_.mesh.tets(t, c));
  const std::vector<int> tris = raw.values<int>("/mesh/tris", H5T_NATIVE_INT, dims);
  ASSERT_EQ(dims, std::vector<hsize_t>({hsize_t(f_.mesh.num_tris()), 3}));
  for (Index t = 0; t < f_.mesh.num_tris(); ++t)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(tris[3 * t + c], f_.mesh.tris(t, c));
  EXPECT_EQ(raw.values<int>("/mesh/tet_body", H5T_NATIVE_INT, dims), std::vector<int>(12, 0));
  EXPECT_EQ(raw.values<int>("/mesh/tri_body", H5T_NATIVE_INT, dims),
            std::vector<int>(f_.mesh.num_tris(), 0));
  EXPECT_EQ(raw.values<int>("/mesh/tri_tet", H5T_NATIVE_INT, dims),
            std::vector<int>(f_.mesh.tri_tet.begin(), f_.mesh.tri_tet.end()));
  EXPECT_EQ(raw.doubles("/mesh/depth"), std::vector<double>(f_.depth.begin(), f_.depth.end()));
  EXPECT_EQ(raw.strings("/mesh/body_names"), std::vector<std::string>({"block"}));
  EXPECT_EQ(raw.strings("/mesh/body_materials"), std::vector<std::string>({"mooney_rivlin"}));
  EXPECT_EQ(raw.values<int>("/mesh/tet_region", H5T_NATIVE_INT, dims), std::vector<int>(12, -1));
  EXPECT_TRUE(raw.has("/mesh/region_names") && raw.strings("/mesh/region_names").empty());
  EXPECT_TRUE(raw.has("/mesh/region_materials") && raw.strings("/mesh/region_materials").empty());
  EXPECT_FALSE(raw.has("/mesh/blocks")) << "one body: the sidecar uses the scene's datasets";

  EXPECT_EQ(raw.string_attribute("/run", "scene"), f_.info.scene_json);
  EXPECT_EQ(raw.string_attribute("/run", "version"), "0.1.0");
  EXPECT_EQ(raw.string_attribute("/run", "analysis"), "static");
  EXPECT_EQ(raw.string_attribute("/run", "status"), "completed");
  EXPECT_EQ(raw.string_attribute("/run", "message"), "");
  EXPECT_EQ(raw.attribute<int>("/run", "threads", H5T_NATIVE_INT), 2);
  EXPECT_EQ(raw.strings("/run/constraint_names"), f_.info.constraint_names);

  // The reference state: positions X (a view of /mesh/X), no displacement (zeros, no storage).
  EXPECT_TRUE(raw.is_view("/reference/x"));
  EXPECT_EQ(raw.doubles("/reference/x"), X);
  EXPECT_EQ(raw.doubles("/reference/displacement"), std::vector<double>(36, 0.0));
  EXPECT_EQ(raw.storage("/reference/displacement"), 0u);
  EXPECT_FALSE(raw.has("/reference/v"));

  for (int k = 1; k <= 3; ++k) {
    SCOPED_TRACE("step " + std::to_string(k));
    const std::string g = "/steps/00000" + std::to_string(k);
    const StepRecord expected = step_record(k);
    EXPECT_EQ(raw.attribute<int>(g, "index", H5T_NATIVE_INT), k);
    EXPECT_EQ(raw.attribute<double>(g, "load", H5T_NATIVE_DOUBLE), k / 3.0);
    EXPECT_EQ(raw.attribute<int>(g, "newton_iterations", H5T_NATIVE_INT), 2 + k);
    EXPECT_EQ(raw.attribute<int>(g, "linear_iterations", H5T_NATIVE_INT), 10 * k + 1);
    EXPECT_EQ(raw.attribute<double>(g, "energy", H5T_NATIVE_DOUBLE), 0.5 * k);
    EXPECT_EQ(raw.attribute<double>(g, "seconds", H5T_NATIVE_DOUBLE), 0.01 * k);
    EXPECT_EQ(raw.doubles(g + "/x"), row_major(x[k - 1]));
    EXPECT_EQ(raw.dims(g + "/x"), std::vector<hsize_t>({12, 3}));
    EXPECT_EQ(raw.doubles(g + "/displacement"), row_major(x[k - 1] - f_.mesh.X));
    EXPECT_EQ(raw.doubles(g + "/residuals"), expected.residuals);
    EXPECT_EQ(raw.doubles(g + "/reactions"),
              std::vector<double>({1.0 / k, 2, 3, -1.0 / k, -2, -3}));
    EXPECT_EQ(raw.dims(g + "/reactions"), std::vector<hsize_t>({2, 3}));
    EXPECT_FALSE(raw.has(g + "/v"));
    EXPECT_FALSE(raw.has_attribute(g, "kinetic_energy"));  // only with velocities
    for (const char* field : {"stress", "strain", "contact_pressure", "blocks"})
      EXPECT_FALSE(raw.has(g + "/" + field)) << field << " was not asked for";
    EXPECT_EQ(raw.attribute<double>(g, "contact_area", H5T_NATIVE_DOUBLE), expected.contact_area());
    EXPECT_EQ(raw.doubles(g + "/contact_forces"),
              std::vector<double>({0.5 * k, -1, 2, 0, 0, double(k)}));
    EXPECT_EQ(raw.dims(g + "/contact_forces"), std::vector<hsize_t>({2, 3}));
    EXPECT_EQ(raw.doubles(g + "/contact_force_magnitudes"), std::vector<double>({3.0 * k, 4.0}));
    EXPECT_EQ(raw.doubles(g + "/contact_areas"), std::vector<double>({0.01 * k, 0.02}));
  }
  EXPECT_EQ(raw.strings("/run/contact_names"),
            std::vector<std::string>({"block/ball", "obstacle floor"}));

  const ResultsSummary s = read_results_summary(path);
  EXPECT_EQ(s.num_nodes, 12);
  EXPECT_EQ(s.num_tets, 12);
  EXPECT_EQ(s.num_tris, f_.mesh.num_tris());
  EXPECT_EQ(s.body_names, std::vector<std::string>({"block"}));
  EXPECT_EQ(s.analysis, "static");
  EXPECT_EQ(s.status, "completed");
  EXPECT_EQ(s.message, "");
  EXPECT_EQ(s.version, "0.1.0");
  EXPECT_EQ(s.threads, 2);
  EXPECT_EQ(s.num_steps, 3);
  EXPECT_EQ(s.last_load, 1.0);
  EXPECT_EQ(s.total_newton_iterations, 3 + 4 + 5);
  EXPECT_EQ(s.total_linear_iterations, 11 + 21 + 31);
  // The second write_timing replaced the first; phases keep their written (not name) order.
  const std::vector<std::pair<std::string, double>> timing{
      {"solve", 2.5}, {"assembly", 1.5}, {"contact", 0.25}};
  EXPECT_EQ(s.timing, timing);
  for (int k = 1; k <= 3; ++k) EXPECT_EQ(read_step_positions(path, k), x[k - 1]);
  EXPECT_EQ(read_step_dataset(path, 2, "reactions"), step_record(2).reactions);
  EXPECT_EQ(read_step_dataset(path, 2, "residuals"),
            Eigen::Map<const VectorX>(step_record(2).residuals.data(), 4));
}

// Every field a run can ask for: velocities (the initial one in the reference state), element
// fields as given, and the contact fields derived from the per-triangle sums, per unit of the
// triangle's current area.
TEST_F(ResultsFileTest, FieldsOfAStepAndOfTheReferenceState) {
  const fs::path path = dir_ / "fields.h5";
  RunInfo info = f_.info;
  info.analysis = "dynamic";
  info.fields = {
      .velocity = true, .displacement = true, .stress = true, .strain = true, .contact = true};
  info.initial_velocity = Points::Constant(12, 3, 0.25);
  const Index tris = f_.mesh.num_tris();
  const Points x = positions(f_.mesh, 1), v = Points::Constant(12, 3, -0.5);
  StepRecord step = step_record(1);
  step.kinetic_energy = 0.75;
  step.surface.resize(tris);
  step.surface.force.row(2) = Vec3(1, -2, 3).transpose();
  step.surface.magnitude(2) = 4.0;
  step.surface.area(2) = 0.002;
  step.surface.depth_integral(2) = 0.002 * 1e-3;
  const ElementFields elements = element_values(12, 1);
  {
    ResultsFile file(path, f_.mesh, f_.depth, info);
    file.append_step(step, x, &v, &elements);
  }
  const RawFile raw(path);
  EXPECT_EQ(raw.doubles("/reference/v"), std::vector<double>(36, 0.25));
  for (const char* zero : {"stress", "von_mises", "strain", "contact_pressure", "contact_traction",
                           "contact_gap", "contact_fraction"}) {
    const std::string name = std::string("/reference/") + zero;
    const std::vector<double> values = raw.doubles(name);
    EXPECT_FALSE(values.empty()) << name;
    EXPECT_EQ(values, std::vector<double>(values.size(), 0.0)) << name;
    EXPECT_EQ(raw.storage(name), 0u) << name << " must take no space";
  }
  EXPECT_EQ(raw.doubles("/reference/volume_ratio"), std::vector<double>(12, 1.0));

  const std::string g = "/steps/000001";
  EXPECT_EQ(raw.doubles(g + "/v"), std::vector<double>(36, -0.5));
  EXPECT_EQ(raw.attribute<double>(g, "kinetic_energy", H5T_NATIVE_DOUBLE), 0.75);
  EXPECT_EQ(raw.doubles(g + "/stress"), row_major(elements.stress));
  EXPECT_EQ(raw.dims(g + "/stress"), std::vector<hsize_t>({12, 6}));
  EXPECT_EQ(raw.doubles(g + "/strain"), row_major(elements.strain));
  EXPECT_EQ(raw.doubles(g + "/von_mises"), row_major(elements.von_mises));
  EXPECT_EQ(raw.doubles(g + "/volume_ratio"), row_major(elements.volume_ratio));
  // Triangle 2 at x: its current area A.
  const Vec3 a = x.row(f_.mesh.tris(2, 0)), b = x.row(f_.mesh.tris(2, 1)),
             c = x.row(f_.mesh.tris(2, 2));
  const double A = 0.5 * (b - a).cross(c - a).norm();
  std::vector<double> pressure(tris, 0.0), gap(tris, 0.0), fraction(tris, 0.0),
      traction(3 * tris, 0.0);
  pressure[2] = 4.0 / A;
  gap[2] = 1e-3;
  fraction[2] = 0.002 / A;
  for (int k = 0; k < 3; ++k) traction[6 + k] = step.surface.force(2, k) / A;
  const auto near = [](const std::vector<double>& got, const std::vector<double>& expected) {
    ASSERT_EQ(got.size(), expected.size());
    for (size_t i = 0; i < got.size(); ++i)
      EXPECT_NEAR(got[i], expected[i], 1e-14 * std::abs(expected[i])) << "entry " << i;
  };
  near(raw.doubles(g + "/contact_pressure"), pressure);
  near(raw.doubles(g + "/contact_traction"), traction);
  near(raw.doubles(g + "/contact_gap"), gap);
  near(raw.doubles(g + "/contact_fraction"), fraction);
}

TEST_F(ResultsFileTest, NoDepthWithoutMaterialDepthContact) {
  const fs::path path = dir_ / "failed.h5";
  {
    ResultsFile file(path, f_.mesh, VectorX(), f_.info);
    file.finish(false, "step 1: Newton did not converge");
  }
  EXPECT_FALSE(RawFile(path).has("/mesh/depth"));
  EXPECT_EQ(read_text(dir_ / "failed.xmf").find("Name=\"depth\""), std::string::npos);
  const ResultsSummary s = read_results_summary(path);
  EXPECT_EQ(s.status, "failed");
  EXPECT_EQ(s.message, "step 1: Newton did not converge");
  EXPECT_EQ(s.num_steps, 0);
  EXPECT_TRUE(s.timing.empty());
}

TEST_F(ResultsFileTest, KilledWriterKeepsCompletedSteps) {
  const fs::path path = dir_ / "killed.h5";
  const Points x1 = positions(f_.mesh, 1), x2 = positions(f_.mesh, 2);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // writes two steps, then dies without closing the file or running destructors
    try {
      ResultsFile file(path, f_.mesh, f_.depth, f_.info);
      file.append_step(step_record(1), x1, nullptr);
      file.append_step(step_record(2), x2, nullptr);
      _exit(3);
    } catch (...) {
      _exit(4);
    }
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 3) << "the child failed to write";

  const ResultsSummary s = read_results_summary(path);
  EXPECT_EQ(s.status, "running");
  EXPECT_EQ(s.num_steps, 2);
  EXPECT_EQ(s.last_load, 2 / 3.0);
  EXPECT_EQ(read_step_positions(path, 1), x1);
  EXPECT_EQ(read_step_positions(path, 2), x2);
  EXPECT_THROW(read_step_positions(path, 3), InputError);
  // The sidecar is complete: the reference state and both steps, closed.
  const std::string xmf = read_text(dir_ / "killed.xmf");
  EXPECT_NE(xmf.find("killed.h5:/steps/000002/x<"), std::string::npos);
  EXPECT_EQ(xmf.substr(xmf.size() - 8), "</Xdmf>\n");
}

// Two bodies: each gets body-local tets and row views of the node and tet datasets.
TEST_F(ResultsFileTest, EveryBodyViewsItsOwnRows) {
  const fs::path path = dir_ / "bodies.h5";
  const Mesh mesh = two_bodies();
  RunInfo info{"{}", "0.1.0", "static", 1, {}, {"neo_hookean", "rigid"}, {}, {}, {}};
  info.fields.stress = info.fields.strain = true;
  const Points x = positions(mesh, 1);
  const ElementFields elements = write_one_step(path, mesh, info);
  const RawFile raw(path);
  std::vector<hsize_t> dims;
  for (Index b = 0; b < 2; ++b) {
    const Body& body = mesh.bodies[b];
    SCOPED_TRACE(body.name);
    const std::string mesh_block = "/mesh/blocks/" + std::to_string(b);
    const std::vector<int> local = raw.values<int>(mesh_block + "/tets", H5T_NATIVE_INT, dims);
    EXPECT_EQ(dims, std::vector<hsize_t>({hsize_t(body.num_tets), 4}));
    for (Index t = 0; t < body.num_tets; ++t)
      for (int c = 0; c < 4; ++c)
        EXPECT_EQ(local[4 * t + c], mesh.tets(body.first_tet + t, c) - body.first_node);
    for (const std::string group : {"/reference", "/steps/000001"}) {
      const std::string here = group + "/blocks/" + std::to_string(b) + "/";
      const Points& positions = group == "/reference" ? mesh.X : x;
      EXPECT_TRUE(raw.is_view(here + "x"));
      EXPECT_EQ(raw.doubles(here + "x"),
                row_major(positions.middleRows(body.first_node, body.num_nodes)));
      EXPECT_EQ(raw.doubles(here + "displacement"),
                row_major((positions - mesh.X).middleRows(body.first_node, body.num_nodes)));
      if (group == "/reference") continue;
      EXPECT_EQ(raw.doubles(here + "stress"),
                row_major(elements.stress.middleRows(body.first_tet, body.num_tets)));
      EXPECT_EQ(raw.doubles(here + "volume_ratio"),
                row_major(elements.volume_ratio.segment(body.first_tet, body.num_tets)));
    }
  }
}

// A body with two element regions (interleaved in its mesh: every third tet in "patella") between
// a body without regions and one with a single region: the sidecar shows four blocks, the
// two-region body as one per region, named after body, region and the region's material, with
// the body's nodes and the region's tets, in the regions' order in the body (patella first: tet 0
// is in it). Every block's tets (block-local) are its region's tets of the original mesh in their
// order, and the per-tet fields it views are the rows of those tets.
TEST_F(ResultsFileTest, EveryRegionOfABodyIsABlockOfItsOwn) {
  const fs::path path = dir_ / "regions.h5";
  const TetMesh cube = box_mesh({Vec3(0, 0, 0), Vec3(1, 1, 1), Eigen::Vector3i(1, 1, 1)});
  const TetMesh leg = box_mesh({Vec3(2, 0, 0), Vec3(3, 1, 2), Eigen::Vector3i(1, 1, 2)});
  const TetMesh bone = box_mesh({Vec3(4, 0, 0), Vec3(5, 1, 1), Eigen::Vector3i(1, 1, 1)});
  std::vector<Index> tet_region;  // into {"soft", "patella"}
  std::vector<std::vector<Index>> original(2);
  for (Index t = 0; t < leg.tets.rows(); ++t) {
    tet_region.push_back(t % 3 == 0 ? 1 : 0);
    original[tet_region.back()].push_back(t);
  }
  Mesh mesh;
  mesh.add_body("plain", cube);
  mesh.add_body("leg", leg, {}, {"soft", "patella"}, tet_region);
  mesh.add_body("bone", bone, {}, {"cortical"}, std::vector<Index>(bone.tets.rows(), 0));
  RunInfo info{"{}",
               "0.1.0",
               "static",
               1,
               {},
               {"neo_hookean", "mooney_rivlin, neo_hookean", "rigid"},
               {"neo_hookean", "mooney_rivlin", "rigid"},
               {.stress = true, .strain = true},
               {}};
  const Points x = positions(mesh, 1);
  const ElementFields elements = write_one_step(path, mesh, info);
  const RawFile raw(path);
  std::vector<hsize_t> dims;
  EXPECT_EQ(raw.strings("/mesh/region_names"),
            std::vector<std::string>({"patella", "soft", "cortical"}));
  EXPECT_EQ(raw.strings("/mesh/region_materials"), info.region_materials);
  std::vector<int> tet_region_file(6, -1);  // "plain": no region
  tet_region_file.insert(tet_region_file.end(), original[1].size(), 0);
  tet_region_file.insert(tet_region_file.end(), original[0].size(), 1);
  tet_region_file.insert(tet_region_file.end(), 6, 2);
  EXPECT_EQ(raw.values<int>("/mesh/tet_region", H5T_NATIVE_INT, dims), tet_region_file);

  struct Expected {
    std::string name;
    Index first_node, first_tet;
    std::vector<Index> tets;  // of the body's own mesh
    const TetMesh* body;
  };
  const Body &plain = mesh.bodies[0], &in_leg = mesh.bodies[1], &in_bone = mesh.bodies[2];
  const std::vector<Index> all6 = {0, 1, 2, 3, 4, 5};
  const std::vector<Expected> blocks = {
      {"plain (neo_hookean)", plain.first_node, plain.first_tet, all6, &cube},
      {"leg/patella (neo_hookean)", in_leg.first_node, in_leg.first_tet, original[1], &leg},
      {"leg/soft (mooney_rivlin)", in_leg.first_node, in_leg.first_tet + Index(original[1].size()),
       original[0], &leg},
      {"bone (rigid)", in_bone.first_node, in_bone.first_tet, all6, &bone}};
  const std::string xmf = read_text(dir_ / "regions.xmf");
  for (size_t k = 0; k < blocks.size(); ++k) {
    const Expected& e = blocks[k];
    SCOPED_TRACE(e.name);
    const Index num_nodes = Index(e.body->X.rows()), num_tets = Index(e.tets.size());
    const std::string block = "blocks/" + std::to_string(k) + "/";
    // In the sidecar, once per state: the block's name, then its tets and points.
    const std::string grid =
        "<Grid Name=\"" + e.name +
        "\" GridType=\"Uniform\">\n"
        "          <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"" +
        std::to_string(num_tets) + "\"><DataItem Dimensions=\"" + std::to_string(num_tets) +
        " 4\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">regions.h5:/mesh/" + block +
        "tets</DataItem></Topology>\n";
    const size_t first = xmf.find(grid);
    EXPECT_NE(first, std::string::npos);
    EXPECT_NE(xmf.find(grid, first + 1), std::string::npos) << "in the reference and the step";
    EXPECT_NE(xmf.find("<Geometry GeometryType=\"XYZ\"><DataItem Dimensions=\"" +
                       std::to_string(num_nodes) +
                       " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">regions.h5:"
                       "/steps/000001/" +
                       block + "x<"),
              std::string::npos);
    EXPECT_EQ(raw.string_attribute("/mesh/" + block.substr(0, block.size() - 1), "name"), e.name);
    // Block-local tets: the region's tets of the body's mesh, in their order.
    const std::vector<int> local = raw.values<int>("/mesh/" + block + "tets", H5T_NATIVE_INT, dims);
    ASSERT_EQ(dims, std::vector<hsize_t>({hsize_t(num_tets), 4}));
    for (Index t = 0; t < num_tets; ++t)
      for (int c = 0; c < 4; ++c)
        EXPECT_EQ(local[4 * t + c], e.body->tets(e.tets[t], c)) << "tet " << t;
    // Views: the body's nodes, the region's rows of the tet fields.
    const std::string here = "/steps/000001/" + block;
    EXPECT_EQ(raw.doubles(here + "x"), row_major(x.middleRows(e.first_node, num_nodes)));
    EXPECT_EQ(raw.doubles(here + "stress"),
              row_major(elements.stress.middleRows(e.first_tet, num_tets)));
    EXPECT_EQ(raw.doubles(here + "volume_ratio"),
              row_major(elements.volume_ratio.segment(e.first_tet, num_tets)));
  }
  EXPECT_EQ(xmf.find("<Grid Name=\"leg"), xmf.find("<Grid Name=\"leg/patella"))
      << "no block for the whole two-region body";
}

// The sidecar: one temporal collection of states (the reference state at time 0, then every step
// at its exact load), each a spatial collection of one tetrahedral grid per body, named after the
// body and its material, and the boundary grid with the step's values as field data. Every HDF5
// dataset it names exists in the results file with the dimensions it states.
TEST_F(ResultsFileTest, XdmfSidecarStructure) {
  const fs::path path = dir_ / "sidecar.h5";
  const Mesh mesh = two_bodies();
  RunInfo info{"{}", "0.1.0", "dynamic", 1, {"clamp"}, {"neo_hookean", "rigid"}, {}, {}, {}};
  info.fields = {
      .velocity = true, .displacement = true, .stress = true, .strain = true, .contact = true};
  info.initial_velocity = Points::Zero(mesh.num_nodes(), 3);
  const VectorX depth = VectorX::LinSpaced(mesh.num_nodes(), 0, 1);
  std::vector<std::string> texts;
  {
    ResultsFile file(path, mesh, depth, info);
    texts.push_back(read_text(dir_ / "sidecar.xmf"));
    for (int k = 1; k <= 2; ++k) {
      StepRecord s = step_record(k);
      s.load = k == 1 ? 0.44 : 0.5;
      s.reactions = Eigen::Matrix<double, 1, 3>(1.5, -2, 0.1 * k);
      s.surface.resize(mesh.num_tris());
      const Points x = positions(mesh, k);
      const ElementFields e = element_values(mesh.num_tets(), k);
      file.append_step(s, x, &x, &e);
      texts.push_back(read_text(dir_ / "sidecar.xmf"));
    }
  }
  const std::string& xmf = texts.back();
  const auto count = [&](const std::string& what) {
    size_t n = 0;
    for (size_t at = xmf.find(what); at != std::string::npos; at = xmf.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("CollectionType=\"Temporal\""), 1u);
  EXPECT_EQ(count("CollectionType=\"Spatial\""), 3u);
  EXPECT_EQ(count("<Grid Name=\"reference\" GridType=\"Collection\""), 1u);
  EXPECT_EQ(count("<Time Value=\"0\"/>"), 1u);
  EXPECT_EQ(count("<Time Value=\"0.44\"/>"), 1u);
  EXPECT_EQ(count("<Time Value=\"0.5\"/>"), 1u);
  EXPECT_EQ(count("<Grid Name=\"left (neo_hookean)\" GridType=\"Uniform\">"), 3u);
  EXPECT_EQ(count("<Grid Name=\"right (rigid)\" GridType=\"Uniform\">"), 3u);
  EXPECT_EQ(count("<Grid Name=\"boundary\" GridType=\"Uniform\">"), 3u);
  // Per step: step, load, settling, newton_iterations, linear_iterations, residual, energy,
  // kinetic_energy, the reaction, the total contact area and three values per interface; none
  // for the reference.
  EXPECT_EQ(count("Center=\"Grid\""), 2u * 16);
  EXPECT_EQ(count("<Attribute Name=\"energy\" AttributeType=\"Scalar\" Center=\"Grid\"><DataItem "
                  "Dimensions=\"1\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">1<"),
            1u);
  EXPECT_EQ(count("<Attribute Name=\"reaction clamp\" AttributeType=\"Vector\" Center=\"Grid\">"
                  "<DataItem Dimensions=\"1 3\" NumberType=\"Float\" Precision=\"8\" "
                  "Format=\"XML\">1.5 -2 0.2<"),
            1u);
  EXPECT_EQ(count("contact_force block/ball"), 2u);
  for (const char* name :
       {"displacement", "velocity", "depth", "stress", "von_mises", "strain", "volume_ratio"})
    EXPECT_EQ(
        count("<Attribute Name=\"" + std::string(name) + "\""),
        3u * 2 + (name == std::string("displacement") || name == std::string("depth") ? 3 : 0))
        << name;
  EXPECT_EQ(count("<Attribute Name=\"contact_pressure\""), 3u);
  EXPECT_EQ(count(dir_.string()), 0u) << "the HDF5 file must be referenced relatively";
  EXPECT_EQ(xmf.substr(xmf.size() - 8), "</Xdmf>\n");

  // Every HDF5 dataset it names, with its dimensions.
  const RawFile raw(path);
  const std::regex item(
      R"re(<DataItem Dimensions="([0-9 ]+)" NumberType="(Float|Int)" Precision="(4|8)" Format="HDF">sidecar\.h5:([^<]+)</DataItem>)re");
  size_t items = 0;
  for (std::sregex_iterator m(xmf.begin(), xmf.end(), item), end; m != end; ++m, ++items) {
    const std::string dataset = (*m)[4];
    SCOPED_TRACE(dataset);
    ASSERT_TRUE(raw.has(dataset));
    std::string dims;
    for (const hsize_t d : raw.dims(dataset)) dims += (dims.empty() ? "" : " ") + std::to_string(d);
    EXPECT_EQ(dims, (*m)[1].str());
  }
  EXPECT_EQ(items, 3u * (2 * 9 + 9)) << "per state: 2 blocks x 9 items, boundary 9";

  // Each step was appended: what was written before (less the closing tags) stays as it was.
  for (size_t k = 1; k < texts.size(); ++k) {
    const std::string before =
        texts[k - 1].substr(0, texts[k - 1].rfind("    </Grid>\n  </Domain>"));
    EXPECT_EQ(texts[k].compare(0, before.size(), before), 0) << "step " << k << " rewrote the file";
  }
}

// ParaView shows one state per distinct time: the settling steps of a static run, all at load 1,
// follow the loading at times 2, 3, ... (their load stays 1 in the file and the field data).
TEST_F(ResultsFileTest, SettlingStepsGetTimesOfTheirOwn) {
  const fs::path path = dir_ / "settle.h5";
  {
    ResultsFile file(path, f_.mesh, f_.depth, f_.info);
    for (int k = 1; k <= 4; ++k) {
      StepRecord s = step_record(k);
      s.load = k == 1 ? 0.5 : 1.0;
      s.settling = k > 2;
      file.append_step(s, positions(f_.mesh, k), nullptr);
    }
  }
  const std::string xmf = read_text(dir_ / "settle.xmf");
  std::vector<std::string> times;
  const std::regex time(R"re(<Time Value="([^"]+)"/>)re");
  for (std::sregex_iterator m(xmf.begin(), xmf.end(), time), end; m != end; ++m)
    times.push_back((*m)[1]);
  EXPECT_EQ(times, std::vector<std::string>({"0", "0.5", "1", "2", "3"}));
  EXPECT_EQ(RawFile(path).attribute<double>("/steps/000004", "load", H5T_NATIVE_DOUBLE), 1.0);
}

TEST_F(ResultsFileTest, RejectsStepsThatDoNotMatchTheRun) {
  const fs::path path = dir_ / "mismatch.h5";
  ResultsFile file(path, f_.mesh, f_.depth, f_.info);
  const Points x = positions(f_.mesh, 1), short_x = x.topRows(5);
  StepRecord s = step_record(1);
  EXPECT_THROW(file.append_step(s, short_x, nullptr), InputError);
  EXPECT_THROW(file.append_step(s, x, &x), InputError) << "velocities in a static run";
  s.reactions.resize(1, 3);
  EXPECT_THROW(file.append_step(s, x, nullptr), InputError);
  s = step_record(1);
  file.append_step(s, x, nullptr);
  StepRecord other_interfaces = step_record(2);
  other_interfaces.contact.pop_back();
  EXPECT_THROW(file.append_step(other_interfaces, x, nullptr), InputError);
  try {
    file.append_step(s, x, nullptr);
    FAIL() << "a step written twice was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/steps/000001"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ResultsFile(dir_ / "no_such_dir" / "x.h5", f_.mesh, f_.depth, f_.info), InputError);

  RunInfo fields = f_.info;
  fields.fields = {
      .velocity = true, .displacement = true, .stress = true, .strain = false, .contact = true};
  fields.initial_velocity = Points::Zero(12, 3);
  ResultsFile more(dir_ / "more.h5", f_.mesh, f_.depth, fields);
  StepRecord t = step_record(1);
  t.surface.resize(f_.mesh.num_tris());
  const ElementFields e = element_values(12, 1);
  EXPECT_THROW(more.append_step(t, x, nullptr, &e), InputError) << "velocities missing";
  EXPECT_THROW(more.append_step(t, x, &x, nullptr), InputError) << "element fields missing";
  StepRecord no_surface = step_record(1);
  EXPECT_THROW(more.append_step(no_surface, x, &x, &e), InputError) << "surface missing";
  more.append_step(t, x, &x, &e);
  fields.initial_velocity = Points::Zero(11, 3);
  EXPECT_THROW(ResultsFile(dir_ / "v.h5", f_.mesh, f_.depth, fields), InputError);
}

// Runs `read`, which must throw InputError with a message that names `path` and contains `what`.
template <class Read>
void expect_input_error(const Read& read, const fs::path& path, const std::string& what) {
  try {
    read();
    FAIL() << "no InputError for " << path;
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }
}

TEST_F(ResultsFileTest, ReadingRejectsMissingAndForeignFiles) {
  const fs::path missing = dir_ / "missing.h5", text = dir_ / "text.h5", other = dir_ / "other.h5";
  std::ofstream(text) << "not an HDF5 file\n";
  H5Fclose(H5Fcreate(other.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  expect_input_error([&] { read_results_summary(missing); }, missing, "no such results file");
  expect_input_error([&] { read_results_summary(text); }, text, "HDF5");
  expect_input_error([&] { read_results_summary(other); }, other, "not a depthfem results file");
  expect_input_error([&] { read_step_positions(text, 0); }, text, "HDF5");
  const fs::path run = dir_ / "run.h5";
  {
    ResultsFile file(run, f_.mesh, f_.depth, f_.info);
    file.append_step(step_record(1), positions(f_.mesh, 1), nullptr);
  }
  expect_input_error([&] { read_step_dataset(run, 1, "stress"); }, run,
                     "no dataset /steps/000001/stress");
  expect_input_error([&] { read_step_dataset(run, 4, "x"); }, run, "no step 4");
}

}  // namespace
}  // namespace depthfem
