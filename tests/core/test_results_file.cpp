// Results files: exact round trip of mesh, run metadata, steps and timing through the HDF5 C API,
// completed steps surviving a killed writer, the XDMF sidecar, and errors naming the file.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
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
  RunInfo info{R"({"name": "squeeze", "steps": 3})", "0.1.0", "static", 2, {"bottom", "top"}};
};

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
  const Points v = Points::Constant(f_.mesh.num_nodes(), 3, 0.125);
  {
    ResultsFile file(path, f_.mesh, f_.depth, f_.info);
    for (int k = 1; k <= 3; ++k) {
      StepRecord s = step_record(k);
      s.kinetic_energy = 0.75 * k;
      file.append_step(s, x[k - 1], k == 2 ? &v : nullptr);
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
  for (Index n = 0; n < 12; ++n)  // row-major in the file, column-major in memory
    for (int c = 0; c < 3; ++c) EXPECT_EQ(X[3 * n + c], f_.mesh.X(n, c));
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
  EXPECT_EQ(raw.values<double>("/mesh/depth", H5T_NATIVE_DOUBLE, dims),
            std::vector<double>(f_.depth.begin(), f_.depth.end()));
  EXPECT_EQ(raw.strings("/mesh/body_names"), std::vector<std::string>({"block"}));

  EXPECT_EQ(raw.string_attribute("/run", "scene"), f_.info.scene_json);
  EXPECT_EQ(raw.string_attribute("/run", "version"), "0.1.0");
  EXPECT_EQ(raw.string_attribute("/run", "analysis"), "static");
  EXPECT_EQ(raw.string_attribute("/run", "status"), "completed");
  EXPECT_EQ(raw.string_attribute("/run", "message"), "");
  EXPECT_EQ(raw.attribute<int>("/run", "threads", H5T_NATIVE_INT), 2);
  EXPECT_EQ(raw.strings("/run/constraint_names"), f_.info.constraint_names);

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
    const std::vector<double> xk = raw.values<double>(g + "/x", H5T_NATIVE_DOUBLE, dims);
    ASSERT_EQ(dims, std::vector<hsize_t>({12, 3}));
    for (Index n = 0; n < 12; ++n)
      for (int c = 0; c < 3; ++c) EXPECT_EQ(xk[3 * n + c], x[k - 1](n, c));
    EXPECT_EQ(raw.values<double>(g + "/residuals", H5T_NATIVE_DOUBLE, dims), expected.residuals);
    EXPECT_EQ(raw.values<double>(g + "/reactions", H5T_NATIVE_DOUBLE, dims),
              std::vector<double>({1.0 / k, 2, 3, -1.0 / k, -2, -3}));
    EXPECT_EQ(dims, std::vector<hsize_t>({2, 3}));
    EXPECT_EQ(raw.has((g + "/v").c_str()), k == 2);
    EXPECT_EQ(raw.has_attribute(g, "kinetic_energy"), k == 2);  // only with velocities
    EXPECT_EQ(raw.attribute<double>(g, "contact_area", H5T_NATIVE_DOUBLE), expected.contact_area());
    EXPECT_EQ(raw.values<double>(g + "/contact_forces", H5T_NATIVE_DOUBLE, dims),
              std::vector<double>({0.5 * k, -1, 2, 0, 0, double(k)}));
    EXPECT_EQ(dims, std::vector<hsize_t>({2, 3}));
    EXPECT_EQ(raw.values<double>(g + "/contact_force_magnitudes", H5T_NATIVE_DOUBLE, dims),
              std::vector<double>({3.0 * k, 4.0}));
    EXPECT_EQ(raw.values<double>(g + "/contact_areas", H5T_NATIVE_DOUBLE, dims),
              std::vector<double>({0.01 * k, 0.02}));
  }
  EXPECT_EQ(raw.values<double>("/steps/000002/v", H5T_NATIVE_DOUBLE, dims),
            std::vector<double>(36, 0.125));
  EXPECT_EQ(raw.attribute<double>("/steps/000002", "kinetic_energy", H5T_NATIVE_DOUBLE), 1.5);
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
}

TEST_F(ResultsFileTest, FailedRunKeepsMessageAndEmptyDepthIsZero) {
  const fs::path path = dir_ / "failed.h5";
  {
    ResultsFile file(path, f_.mesh, VectorX(), f_.info);
    file.finish(false, "step 1: Newton did not converge");
  }
  const RawFile raw(path);
  std::vector<hsize_t> dims;
  EXPECT_EQ(raw.values<double>("/mesh/depth", H5T_NATIVE_DOUBLE, dims), std::vector<double>(12, 0));
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
}

TEST_F(ResultsFileTest, XdmfSidecarListsEveryStepRelatively) {
  const fs::path path = dir_ / "sidecar.h5";
  const Points x1 = positions(f_.mesh, 1), x2 = positions(f_.mesh, 2);
  ResultsFile file(path, f_.mesh, f_.depth, f_.info);
  StepRecord s1 = step_record(1), s2 = step_record(2);
  s1.load = 0.25;
  s2.load = 1.5;
  file.append_step(s1, x1, nullptr);
  file.append_step(s2, x2, nullptr);

  std::ifstream in(dir_ / "sidecar.xmf");
  ASSERT_TRUE(in) << "no sidecar";
  std::stringstream text;
  text << in.rdbuf();
  const std::string xmf = text.str();
  const auto count = [&](const std::string& what) {
    size_t n = 0;
    for (size_t at = xmf.find(what); at != std::string::npos; at = xmf.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<Grid"), 3u);  // the temporal collection and one grid per step
  EXPECT_EQ(count("CollectionType=\"Temporal\""), 1u);
  EXPECT_EQ(count("<Time Value=\"0.25\"/>"), 1u);
  EXPECT_EQ(count("<Time Value=\"1.5\"/>"), 1u);
  EXPECT_EQ(count(">sidecar.h5:/steps/000001/x<"), 1u);
  EXPECT_EQ(count(">sidecar.h5:/steps/000002/x<"), 1u);
  EXPECT_EQ(count(">sidecar.h5:/mesh/tets<"), 2u);
  EXPECT_EQ(count(dir_.string()), 0u) << "the HDF5 file must be referenced relatively";
  EXPECT_EQ(xmf.substr(xmf.size() - 8), "</Xdmf>\n");
  EXPECT_FALSE(fs::exists(dir_ / "sidecar.xmf.tmp"));
}

TEST_F(ResultsFileTest, RejectsStepsThatDoNotMatchTheMesh) {
  const fs::path path = dir_ / "mismatch.h5";
  ResultsFile file(path, f_.mesh, f_.depth, f_.info);
  const Points x = positions(f_.mesh, 1), short_x = x.topRows(5);
  StepRecord s = step_record(1);
  EXPECT_THROW(file.append_step(s, short_x, nullptr), InputError);
  EXPECT_THROW(file.append_step(s, x, &short_x), InputError);
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
}

}  // namespace
}  // namespace depthfem
