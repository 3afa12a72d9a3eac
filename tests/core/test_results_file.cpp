// Results files: exact round trip of mesh, run metadata, the reference state, steps, fields and
// timing through the HDF5 C API; per-body and per-region blocks; completed steps surviving a
// killed writer and a full disk; a second writer refused; the XDMF sidecars' structure (every
// dataset they name exists with the dimensions they state, and the parts they select hold the
// expected values) and their step-by-step growth; errors naming the file; damaged and foreign files
// (datasets of another shape, type or value, flipped bytes, another mesh) refused in one line
// naming the file and the dataset, without waiting.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <numeric>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/hdf5_file.hpp"
#include "core/mesh.hpp"
#include "core/mesh_generators.hpp"
#include "core/results_file.hpp"

namespace depthfem {
namespace {

namespace fs = std::filesystem;

// Reads through the HDF5 C API directly, so that the writer is not checked by its own reader.
// Failures show as empty or zero values, which the expectations then reject. Opens as a SWMR
// reader (a killed writer's file needs it) without file locks like depthfem does: HDF5 refuses
// to open a file twice with different locking settings.
class RawFile {
 public:
  explicit RawFile(const fs::path& path) {
    const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(access, false, true);
    id_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, access);
    H5Pclose(access);
  }
  bool is_open() const { return id_ >= 0; }
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
  // Where the data of a contiguous dataset begin in the file.
  haddr_t offset(const std::string& name) const {
    const hid_t set = H5Dopen2(id_, name.c_str(), H5P_DEFAULT);
    const haddr_t at = H5Dget_offset(set);
    H5Dclose(set);
    return at;
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
  // Row `row` of a /steps dataset (all rows at once is values()).
  std::vector<double> row(const std::string& name, hsize_t row) const {
    std::vector<hsize_t> dims = this->dims(name), start(dims.size(), 0);
    start[0] = row;
    dims[0] = 1;
    return slab(name, start, dims);
  }
  // The hyperslab from `start` of `count` values in each dimension, as doubles, row-major.
  std::vector<double> slab(const std::string& name, const std::vector<hsize_t>& start,
                           const std::vector<hsize_t>& count) const {
    const hid_t set = H5Dopen2(id_, name.c_str(), H5P_DEFAULT), space = H5Dget_space(set);
    const hid_t memory = H5Screate_simple(int(count.size()), count.data(), nullptr);
    std::vector<double> out(std::max<hssize_t>(H5Sget_simple_extent_npoints(memory), 0));
    if (H5Sselect_hyperslab(space, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) <
            0 ||
        H5Dread(set, H5T_NATIVE_DOUBLE, memory, space, H5P_DEFAULT, out.data()) < 0)
      out.clear();
    H5Sclose(memory);
    H5Sclose(space);
    H5Dclose(set);
    return out;
  }
  // A scalar dataset of one fixed-length string (NUL padded).
  std::string text(const std::string& name) const {
    const hid_t set = H5Dopen2(id_, name.c_str(), H5P_DEFAULT), type = H5Dget_type(set);
    std::string out(std::max<size_t>(H5Tget_size(type), 0), '\0');
    if (out.empty() || H5Tis_variable_str(type) != 0 ||
        H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
      out = "<not a fixed-length string>";
    H5Tclose(type);
    H5Dclose(set);
    return out.substr(0, out.find('\0'));
  }
  // The rows of a dataset of fixed-length strings.
  std::vector<std::string> texts(const std::string& name) const {
    const hid_t set = H5Dopen2(id_, name.c_str(), H5P_DEFAULT), type = H5Dget_type(set);
    const hid_t space = H5Dget_space(set);
    const size_t size = H5Tget_size(type);
    const hssize_t n = std::max<hssize_t>(H5Sget_simple_extent_npoints(space), 0);
    std::string buffer(size * size_t(n), '\0');
    std::vector<std::string> out;
    if (n == 0 || H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()) >= 0)
      for (hssize_t k = 0; k < n; ++k) {
        const std::string one = buffer.substr(size * size_t(k), size);
        out.push_back(one.substr(0, one.find('\0')));
      }
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(set);
    return out;
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
  RunInfo info{
      R"({"name": "squeeze", "steps": 3})", "0.1.0",           "static", 2,  {"bottom", "top"},
      {"block/ball", "obstacle floor"},     {"mooney_rivlin"}, {},       {}, {}};
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

// Writes a results file of `mesh` without constraints or contact and with one step:
// positions(mesh, 1) and element_values(#tets, 1), which it returns.
ElementFields write_one_step(const fs::path& path, const Mesh& mesh, const RunInfo& info) {
  const ElementFields elements = element_values(mesh.num_tets(), 1);
  StepRecord step = step_record(1);
  step.reactions.resize(0, 3);
  step.contact.clear();
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

// A DataItem of a sidecar that reads an HDF5 dataset: the whole dataset, or the part that a
// selection names (Xdmf3: "FILE:DATASET|start:stride:count:dims"; XDMF 2: a HyperSlab item).
struct SidecarItem {
  std::string dataset;
  std::vector<hsize_t> shape;  // the item's Dimensions: the shape the reader gets
  std::vector<hsize_t> dims;   // the dataset's dimensions as the sidecar states them
  std::vector<hsize_t> start, count;
  bool selection = false;
};

std::vector<hsize_t> numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<hsize_t> out;
  for (hsize_t v; in >> v;) out.push_back(v);
  return out;
}

// Every item of `xmf` that reads from `h5_name`, in order; `unparsed` counts those that name the
// file in another form (which the expectations reject).
std::vector<SidecarItem> sidecar_items(const std::string& xmf, const std::string& h5_name,
                                       size_t& unparsed) {
  const std::string file = std::regex_replace(h5_name, std::regex(R"(\.)"), R"(\.)");
  const std::string hdf =
      R"re(NumberType="(?:Float|Int)" Precision="(?:4|8)" Format="HDF">)re" + file + ":";
  const std::regex plain(
      R"re(<DataItem Dimensions="([0-9 ]+)" )re" + hdf +
      R"re(([^<|]+)(?:\|([0-9 ]+):([0-9 ]+):([0-9 ]+):([0-9 ]+))?</DataItem>)re");
  const std::regex slab(
      R"re(<DataItem ItemType="HyperSlab" Dimensions="([0-9 ]+)" Type="HyperSlab"><DataItem Dimensions="3 ([0-9]+)" Format="XML">([0-9 ]+)</DataItem><DataItem Dimensions="([0-9 ]+)" )re" +
      hdf + R"re(([^<]+)</DataItem></DataItem>)re");
  std::vector<SidecarItem> out;
  size_t named = 0;
  for (size_t at = xmf.find(h5_name + ":"); at != std::string::npos;
       at = xmf.find(h5_name + ":", at + 1))
    ++named;
  for (std::sregex_iterator m(xmf.begin(), xmf.end(), slab), end; m != end; ++m) {
    const std::vector<hsize_t> selection = numbers((*m)[3]);
    const size_t rank = std::stoul((*m)[2]);
    SidecarItem item{(*m)[5], numbers((*m)[1]), numbers((*m)[4]), {}, {}, true};
    if (selection.size() == 3 * rank) {
      item.start.assign(selection.begin(), selection.begin() + long(rank));
      item.count.assign(selection.begin() + 2 * long(rank), selection.end());
      if (!std::all_of(selection.begin() + long(rank), selection.begin() + 2 * long(rank),
                       [](hsize_t s) { return s == 1; }))
        item.count.clear();  // a stride other than 1: rejected below
    }
    out.push_back(item);
  }
  const std::string without_slabs = std::regex_replace(xmf, slab, "");
  for (std::sregex_iterator m(without_slabs.begin(), without_slabs.end(), plain), end; m != end;
       ++m) {
    SidecarItem item{(*m)[2], numbers((*m)[1]), {}, {}, {}, (*m)[3].matched};
    if (item.selection) {
      item.start = numbers((*m)[3]);
      if (numbers((*m)[4]) != std::vector<hsize_t>(item.start.size(), 1)) continue;
      item.count = numbers((*m)[5]);
      item.dims = numbers((*m)[6]);
    }
    out.push_back(item);
  }
  unparsed = named - out.size();
  return out;
}

// Checks every item against the results file: its dataset exists; a whole dataset has the
// stated dimensions; a selection states the dataset's dimensions (for the growing /steps
// datasets: as many rows as the selection needs, at most as many as the file has), lies inside
// them, and has as many values as the item's shape.
void expect_items_in_file(const std::vector<SidecarItem>& items, const RawFile& raw) {
  for (const SidecarItem& item : items) {
    SCOPED_TRACE(item.dataset);
    ASSERT_TRUE(raw.has(item.dataset));
    const std::vector<hsize_t> actual = raw.dims(item.dataset);
    if (!item.selection) {
      EXPECT_EQ(item.shape, actual);
      continue;
    }
    ASSERT_EQ(item.dims.size(), actual.size());
    ASSERT_EQ(item.start.size(), actual.size());
    ASSERT_EQ(item.count.size(), actual.size());
    const bool series = item.dataset.rfind("/steps/", 0) == 0;
    for (size_t d = 0; d < actual.size(); ++d) {
      if (series && d == 0)
        EXPECT_LE(item.dims[0], actual[0]);
      else
        EXPECT_EQ(item.dims[d], actual[d]) << "dimension " << d;
      EXPECT_LE(item.start[d] + item.count[d], item.dims[d]) << "dimension " << d;
    }
    const auto product = [](const std::vector<hsize_t>& v) {
      return std::accumulate(v.begin(), v.end(), hsize_t(1), std::multiplies<>());
    };
    EXPECT_EQ(product(item.count), product(item.shape));
  }
}

// What the reader of `item` gets from the file.
std::vector<double> read_item(const RawFile& raw, const SidecarItem& item) {
  return item.selection ? raw.slab(item.dataset, item.start, item.count)
                        : raw.doubles(item.dataset);
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
  void TearDown() override {
    if (!getenv("KEEP")) fs::remove_all(dir_);
  }

  fs::path dir_;
  Fixture f_;
};

TEST_F(ResultsFileTest, RoundTripOfMeshRunStepsAndTiming) {
  const fs::path path = dir_ / "run.h5";
  std::vector<Points> x;
  for (int k = 1; k <= 3; ++k) x.push_back(positions(f_.mesh, k));
  {
    ResultsFile file(path, f_.mesh, f_.depth, f_.info);
    EXPECT_FALSE(fs::exists(dir_ / ".run.h5.partial")) << "built under this name, then renamed";
    for (int k = 1; k <= 3; ++k) {
      file.append_step(step_record(k), x[k - 1], nullptr);
      // Readable while the writer is open, with every step written so far.
      const ResultsSummary during = read_results_summary(path);
      EXPECT_EQ(during.status, "running");
      EXPECT_EQ(during.num_steps, k);
      EXPECT_EQ(read_step_positions(path, k), x[k - 1]);
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
  EXPECT_EQ(raw.text("/run/status"), "completed");
  EXPECT_EQ(raw.text("/run/message"), "");
  EXPECT_EQ(raw.attribute<int>("/run", "threads", H5T_NATIVE_INT), 2);
  EXPECT_EQ(raw.strings("/run/constraint_names"), f_.info.constraint_names);
  EXPECT_EQ(raw.strings("/run/contact_names"),
            std::vector<std::string>({"block/ball", "obstacle floor"}));

  // The reference state: positions X (a view of /mesh/X), no displacement (zeros, no storage).
  EXPECT_TRUE(raw.is_view("/reference/x"));
  EXPECT_EQ(raw.doubles("/reference/x"), X);
  EXPECT_EQ(raw.doubles("/reference/displacement"), std::vector<double>(36, 0.0));
  EXPECT_EQ(raw.storage("/reference/displacement"), 0u);
  EXPECT_FALSE(raw.has("/reference/v"));

  // The steps: one row each, in the order written.
  EXPECT_EQ(raw.doubles("/steps/index"), std::vector<double>({1, 2, 3}));
  EXPECT_EQ(raw.doubles("/steps/load"), std::vector<double>({1 / 3.0, 2 / 3.0, 1}));
  EXPECT_EQ(raw.doubles("/steps/settling"), std::vector<double>({0, 0, 0}));
  EXPECT_EQ(raw.doubles("/steps/newton_iterations"), std::vector<double>({3, 4, 5}));
  EXPECT_EQ(raw.doubles("/steps/linear_iterations"), std::vector<double>({11, 21, 31}));
  EXPECT_EQ(raw.doubles("/steps/energy"), std::vector<double>({0.5, 1, 1.5}));
  EXPECT_EQ(raw.doubles("/steps/seconds"), std::vector<double>({0.01, 0.02, 0.01 * 3}));
  EXPECT_EQ(raw.doubles("/steps/residual_count"), std::vector<double>({3, 4, 5}));
  std::vector<double> residuals;
  for (int k = 1; k <= 3; ++k)
    for (const double r : step_record(k).residuals) residuals.push_back(r);
  EXPECT_EQ(raw.doubles("/steps/residuals"), residuals);
  EXPECT_EQ(raw.dims("/steps/x"), std::vector<hsize_t>({3, 12, 3}));
  EXPECT_EQ(raw.dims("/steps/reactions"), std::vector<hsize_t>({3, 2, 3}));
  EXPECT_EQ(raw.dims("/steps/contact_forces"), std::vector<hsize_t>({3, 2, 3}));
  for (int k = 1; k <= 3; ++k) {
    SCOPED_TRACE("step " + std::to_string(k));
    const hsize_t row = hsize_t(k - 1);
    const StepRecord expected = step_record(k);
    EXPECT_EQ(raw.row("/steps/x", row), row_major(x[k - 1]));
    EXPECT_EQ(raw.row("/steps/displacement", row), row_major(x[k - 1] - f_.mesh.X));
    EXPECT_EQ(raw.row("/steps/reactions", row),
              std::vector<double>({1.0 / k, 2, 3, -1.0 / k, -2, -3}));
    EXPECT_EQ(raw.row("/steps/contact_area", row), std::vector<double>({expected.contact_area()}));
    EXPECT_EQ(raw.row("/steps/contact_forces", row),
              std::vector<double>({0.5 * k, -1, 2, 0, 0, double(k)}));
    EXPECT_EQ(raw.row("/steps/contact_force_magnitudes", row), std::vector<double>({3.0 * k, 4.0}));
    EXPECT_EQ(raw.row("/steps/contact_areas", row), std::vector<double>({0.01 * k, 0.02}));
    // A run with material-depth contact (it has depths) reports the penetration; these records
    // carry none, which reads as NaN.
    EXPECT_TRUE(std::isnan(raw.row("/steps/penetration", row).at(0)));
  }
  for (const char* field : {"v", "kinetic_energy", "stress", "strain", "contact_pressure"})
    EXPECT_FALSE(raw.has(std::string("/steps/") + field)) << field << " was not asked for";
  EXPECT_EQ(raw.texts("/timing/phases"),
            std::vector<std::string>({"solve", "assembly", "contact"}));
  EXPECT_EQ(raw.doubles("/timing/seconds"), std::vector<double>({2.5, 1.5, 0.25}));

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
  EXPECT_EQ(read_step_dataset(path, 3, "load"), Eigen::MatrixXd::Constant(1, 1, 1.0));
  const StepState last = read_step_state(path);
  EXPECT_EQ(last.index, 3);
  EXPECT_EQ(last.load, 1.0);
  EXPECT_EQ(last.x, x[2]);
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
  step.penetration = 2e-4;
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

  EXPECT_EQ(raw.row("/steps/v", 0), std::vector<double>(36, -0.5));
  EXPECT_EQ(raw.row("/steps/kinetic_energy", 0), std::vector<double>({0.75}));
  EXPECT_EQ(raw.row("/steps/penetration", 0), std::vector<double>({2e-4}));
  EXPECT_EQ(raw.row("/steps/stress", 0), row_major(elements.stress));
  EXPECT_EQ(raw.dims("/steps/stress"), std::vector<hsize_t>({1, 12, 6}));
  EXPECT_EQ(raw.row("/steps/strain", 0), row_major(elements.strain));
  EXPECT_EQ(raw.row("/steps/von_mises", 0), row_major(elements.von_mises));
  EXPECT_EQ(raw.row("/steps/volume_ratio", 0), row_major(elements.volume_ratio));
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
  near(raw.row("/steps/contact_pressure", 0), pressure);
  near(raw.row("/steps/contact_traction", 0), traction);
  near(raw.row("/steps/contact_gap", 0), gap);
  near(raw.row("/steps/contact_fraction", 0), fraction);
}

TEST_F(ResultsFileTest, NoDepthWithoutMaterialDepthContact) {
  const fs::path path = dir_ / "failed.h5";
  {
    ResultsFile file(path, f_.mesh, VectorX(), f_.info);
    file.finish(false, "step 1: Newton did not converge");
  }
  EXPECT_FALSE(RawFile(path).has("/mesh/depth"));
  EXPECT_FALSE(RawFile(path).has("/steps/penetration"));
  for (const std::string& sidecar : results_sidecars(path))
    EXPECT_EQ(read_text(sidecar).find("Name=\"depth\""), std::string::npos) << sidecar;
  const ResultsSummary s = read_results_summary(path);
  EXPECT_EQ(s.status, "failed");
  EXPECT_EQ(s.message, "step 1: Newton did not converge");
  EXPECT_EQ(s.num_steps, 0);
  EXPECT_TRUE(s.timing.empty());
}

// A writer that dies (no destructor, no close) leaves a file whose completed steps every SWMR
// reader finds, and sidecars that list them and are closed.
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
  // The sidecars are complete: the reference state and both steps, closed.
  for (const std::string& sidecar : results_sidecars(path)) {
    SCOPED_TRACE(sidecar);
    const std::string xmf = read_text(sidecar);
    EXPECT_NE(xmf.find("<Grid Name=\"step_1\""), std::string::npos);
    EXPECT_EQ(xmf.substr(xmf.size() - 8), "</Xdmf>\n");
  }
}

// A disk that fills up (here: a limit on the file size, at several sizes so that it fills at
// different moments) makes append_step throw InputError naming the file, never crash, and
// neither does closing the file after it; every step written before stays readable.
TEST_F(ResultsFileTest, FullDiskEndsInAnErrorAndKeepsTheStepsBefore) {
  const Mesh mesh = single_body_mesh(box_mesh({Vec3::Zero(), Vec3::Ones(), {6, 6, 6}}));
  for (const rlim_t room : {1100000, 1234567, 1500000, 2000000, 2345678}) {
    SCOPED_TRACE("room " + std::to_string(room));
    const fs::path path = dir_ / ("full" + std::to_string(room) + ".h5");
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      signal(SIGXFSZ, SIG_IGN);  // writes beyond the limit fail with EFBIG instead
      int code = 5;
      try {
        ResultsFile file(path, mesh, VectorX(), f_.info);
        const rlimit limit{fs::file_size(path) + room, fs::file_size(path) + room};
        setrlimit(RLIMIT_FSIZE, &limit);
        for (int k = 1; k <= 1000; ++k) {
          StepRecord s = step_record(k);
          s.load = k / 1000.0;
          file.append_step(s, positions(mesh, k), nullptr);
        }
        code = 6;  // never full
      } catch (const InputError& e) {
        code = std::string(e.what()).find(path.string()) != std::string::npos ? 3 : 4;
      }
      _exit(code);  // after the writer's destructor
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status)) << "the writer crashed (signal " << WTERMSIG(status) << ")";
    ASSERT_EQ(WEXITSTATUS(status), 3) << "4: an error not naming the file, 6: never full";
    const ResultsSummary s = read_results_summary(path);
    EXPECT_GE(s.num_steps, 1);
    EXPECT_LT(s.num_steps, 1000);
    for (Index k = 1; k <= s.num_steps; ++k)
      EXPECT_EQ(read_step_positions(path, k), positions(mesh, int(k))) << "step " << k;
  }
}

// Two bodies: each is a block of the sidecars with body-local tets, whose items select the
// body's rows of the node and tet datasets of each state.
TEST_F(ResultsFileTest, EveryBodyIsABlockOfItsOwnRows) {
  const fs::path path = dir_ / "bodies.h5";
  const Mesh mesh = two_bodies();
  RunInfo info{"{}", "0.1.0", "static", 1, {}, {}, {"neo_hookean", "rigid"}, {}, {}, {}};
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
  }
  // Per sidecar and state (reference, step 1): block b's items read the body's rows.
  for (const std::string& sidecar : results_sidecars(path)) {
    SCOPED_TRACE(sidecar);
    size_t unparsed = 0;
    const std::vector<SidecarItem> items = sidecar_items(read_text(sidecar), "bodies.h5", unparsed);
    EXPECT_EQ(unparsed, 0u);
    expect_items_in_file(items, raw);
    for (const int state : {0, 1}) {
      const Points& at = state == 0 ? mesh.X : x;
      for (Index b = 0; b < 2; ++b) {
        const Body& body = mesh.bodies[b];
        // The item of `dataset` in this state that selects `count` rows from `first`.
        const auto item = [&](const std::string& dataset, Index first, Index count) {
          const std::string full = (state == 0 ? "/reference/" : "/steps/") + dataset;
          const size_t rows = state == 0 ? 0 : 1;  // the dimension of nodes or tets
          const auto found = std::find_if(items.begin(), items.end(), [&](const SidecarItem& i) {
            return i.dataset == full && i.selection && i.start.size() > rows &&
                   i.start[rows] == hsize_t(first) && i.count[rows] == hsize_t(count);
          });
          return found == items.end() ? SidecarItem{} : *found;
        };
        const auto nodes = [&](const char* dataset) {
          return item(dataset, body.first_node, body.num_nodes);
        };
        const auto tets = [&](const char* dataset) {
          return item(dataset, body.first_tet, body.num_tets);
        };
        EXPECT_EQ(read_item(raw, nodes("x")),
                  row_major(at.middleRows(body.first_node, body.num_nodes)));
        EXPECT_EQ(read_item(raw, nodes("displacement")),
                  row_major((at - mesh.X).middleRows(body.first_node, body.num_nodes)));
        if (state == 0) continue;
        EXPECT_EQ(read_item(raw, tets("stress")),
                  row_major(elements.stress.middleRows(body.first_tet, body.num_tets)));
        EXPECT_EQ(read_item(raw, tets("volume_ratio")),
                  row_major(elements.volume_ratio.segment(body.first_tet, body.num_tets)));
      }
    }
  }
}

// A body with two element regions (interleaved in its mesh: every third tet in "patella") between
// a body without regions and one with a single region: the sidecars show four blocks, the
// two-region body as one per region, named after body, region and the region's material, with
// the body's nodes and the region's tets, in the regions' order in the body (patella first: tet 0
// is in it). Every block's tets (block-local) are its region's tets of the original mesh in their
// order, and the per-tet fields it shows are the rows of those tets.
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
  for (size_t k = 0; k < blocks.size(); ++k) {
    const Expected& e = blocks[k];
    SCOPED_TRACE(e.name);
    const Index num_tets = Index(e.tets.size());
    const std::string block = "/mesh/blocks/" + std::to_string(k);
    EXPECT_EQ(raw.string_attribute(block, "name"), e.name);
    // Block-local tets: the region's tets of the body's mesh, in their order.
    const std::vector<int> local = raw.values<int>(block + "/tets", H5T_NATIVE_INT, dims);
    ASSERT_EQ(dims, std::vector<hsize_t>({hsize_t(num_tets), 4}));
    for (Index t = 0; t < num_tets; ++t)
      for (int c = 0; c < 4; ++c)
        EXPECT_EQ(local[4 * t + c], e.body->tets(e.tets[t], c)) << "tet " << t;
  }
  for (const std::string& sidecar : results_sidecars(path)) {
    SCOPED_TRACE(sidecar);
    const std::string xmf = read_text(sidecar);
    size_t unparsed = 0;
    const std::vector<SidecarItem> items = sidecar_items(xmf, "regions.h5", unparsed);
    EXPECT_EQ(unparsed, 0u);
    expect_items_in_file(items, raw);
    // Per state: 4 blocks of 7 items (tets, x, displacement, stress, von Mises, strain, volume
    // ratio), then the boundary's 4 (triangles, x, body, displacement).
    ASSERT_EQ(items.size(), 2u * (4 * 7 + 4));
    // The step's blocks, as the document lists them, after the blocks of the reference state.
    std::vector<std::string> names;
    const std::regex grid(R"re(<Grid Name="([^"]+)" GridType="Uniform">)re");
    for (std::sregex_iterator m(xmf.begin(), xmf.end(), grid), end; m != end; ++m)
      names.push_back((*m)[1]);
    ASSERT_EQ(names.size(), 2u * 5);
    const std::string xdmf2_order = sidecar.substr(sidecar.size() - 6);
    for (size_t k = 0; k < blocks.size(); ++k) {
      const Expected& e = blocks[k];
      SCOPED_TRACE(e.name);
      const Index num_nodes = Index(e.body->X.rows()), num_tets = Index(e.tets.size());
      EXPECT_EQ(names[5 + k], e.name);
      // The items of block k in the step (the document order of the items of one state).
      const auto of_step = [&](const std::string& dataset) {
        const auto found = std::find_if(items.begin(), items.end(), [&](const SidecarItem& i) {
          return i.dataset == dataset && i.selection && i.start.size() > 1 && i.start[0] == 0 &&
                 i.count[1] == hsize_t(dataset == "/steps/x" ? num_nodes : num_tets) &&
                 i.start[1] == hsize_t(dataset == "/steps/x" ? e.first_node : e.first_tet);
        });
        return found == items.end() ? SidecarItem{} : *found;
      };
      EXPECT_NE(std::find_if(items.begin(), items.end(),
                             [&](const SidecarItem& i) {
                               return i.dataset == "/mesh/blocks/" + std::to_string(k) + "/tets" &&
                                      !i.selection;
                             }),
                items.end());
      EXPECT_EQ(read_item(raw, of_step("/steps/x")),
                row_major(x.middleRows(e.first_node, num_nodes)));
      EXPECT_EQ(read_item(raw, of_step("/steps/stress")),
                row_major(elements.stress.middleRows(e.first_tet, num_tets)));
      EXPECT_EQ(read_item(raw, of_step("/steps/volume_ratio")),
                row_major(elements.volume_ratio.segment(e.first_tet, num_tets)));
    }
    EXPECT_EQ(std::count(names.begin(), names.end(), "leg (mooney_rivlin, neo_hookean)"), 0)
        << "no block for the whole two-region body";
  }
}

// The sidecars: one temporal collection of states (the reference state at time 0, then every
// step at its exact load), each a spatial collection of one tetrahedral grid per body, named
// after the body and its material, and the boundary grid with the step's values as field data.
// Every HDF5 dataset an item names exists in the results file with the dimensions it states, and
// a step's items read that step's row. Each step is appended: what was there stays as it was.
TEST_F(ResultsFileTest, XdmfSidecarStructure) {
  const fs::path path = dir_ / "sidecar.h5";
  const Mesh mesh = two_bodies();
  RunInfo info{"{}",
               "0.1.0",
               "dynamic",
               1,
               {"clamp"},
               {"block/ball", "obstacle floor"},
               {"neo_hookean", "rigid"},
               {},
               {},
               {}};
  info.fields = {
      .velocity = true, .displacement = true, .stress = true, .strain = true, .contact = true};
  info.initial_velocity = Points::Zero(mesh.num_nodes(), 3);
  const VectorX depth = VectorX::LinSpaced(mesh.num_nodes(), 0, 1);
  const std::vector<std::string> sidecars = results_sidecars(path);
  ASSERT_EQ(sidecars.size(), 2u);
  EXPECT_EQ(fs::path(sidecars[0]).filename(), "sidecar.xmf");
  EXPECT_EQ(fs::path(sidecars[1]).filename(), "sidecar.xdmf2");
  std::vector<std::vector<std::string>> texts(2);
  std::vector<Points> x;
  {
    ResultsFile file(path, mesh, depth, info);
    for (size_t d = 0; d < 2; ++d) texts[d].push_back(read_text(sidecars[d]));
    for (int k = 1; k <= 2; ++k) {
      StepRecord s = step_record(k);
      s.load = k == 1 ? 0.44 : 0.5;
      s.reactions = Eigen::Matrix<double, 1, 3>(1.5, -2, 0.1 * k);
      s.surface.resize(mesh.num_tris());
      x.push_back(positions(mesh, k));
      const ElementFields e = element_values(mesh.num_tets(), k);
      file.append_step(s, x.back(), &x.back(), &e);
      for (size_t d = 0; d < 2; ++d) texts[d].push_back(read_text(sidecars[d]));
    }
  }
  const RawFile raw(path);
  for (size_t d = 0; d < 2; ++d) {
    SCOPED_TRACE(sidecars[d]);
    const std::string& xmf = texts[d].back();
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
    // Per step: step, load, settling, newton_iterations, linear_iterations, linear_solves,
    // factorizations, residual, energy, kinetic_energy, the reaction, the total contact area and
    // three values per interface; none for the reference.
    EXPECT_EQ(count("Center=\"Grid\""), 2u * 18);
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

    size_t unparsed = 0;
    const std::vector<SidecarItem> items = sidecar_items(xmf, "sidecar.h5", unparsed);
    EXPECT_EQ(unparsed, 0u);
    EXPECT_EQ(items.size(), 3u * (2 * 9 + 9)) << "per state: 2 blocks x 9 items, boundary 9";
    expect_items_in_file(items, raw);
    // The boundary's positions at each step: all of row k of /steps/x, stated as k + 1 rows.
    for (hsize_t k = 0; k < 2; ++k) {
      const auto boundary = std::find_if(items.begin(), items.end(), [&](const SidecarItem& i) {
        return i.dataset == "/steps/x" && i.start == std::vector<hsize_t>({k, 0, 0}) &&
               i.count == std::vector<hsize_t>({1, hsize_t(mesh.num_nodes()), 3});
      });
      ASSERT_NE(boundary, items.end()) << "step row " << k;
      EXPECT_EQ(boundary->dims, std::vector<hsize_t>({k + 1, hsize_t(mesh.num_nodes()), 3}));
      EXPECT_EQ(read_item(raw, *boundary), row_major(x[k]));
    }

    // Each step was appended: what was written before (less the closing tags) stays as it was.
    for (size_t k = 1; k < texts[d].size(); ++k) {
      const std::string before =
          texts[d][k - 1].substr(0, texts[d][k - 1].rfind("    </Grid>\n  </Domain>"));
      EXPECT_EQ(texts[d][k].compare(0, before.size(), before), 0)
          << "step " << k << " rewrote the file";
    }
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
  for (const std::string& sidecar : results_sidecars(path)) {
    const std::string xmf = read_text(sidecar);
    std::vector<std::string> times;
    const std::regex time(R"re(<Time Value="([^"]+)"/>)re");
    for (std::sregex_iterator m(xmf.begin(), xmf.end(), time), end; m != end; ++m)
      times.push_back((*m)[1]);
    EXPECT_EQ(times, std::vector<std::string>({"0", "0.5", "1", "2", "3"})) << sidecar;
  }
  EXPECT_EQ(RawFile(path).doubles("/steps/load"), std::vector<double>({0.5, 1, 1, 1}));
  EXPECT_EQ(RawFile(path).doubles("/steps/settling"), std::vector<double>({0, 0, 1, 1}));
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
  StepRecord other_interfaces = step_record(1);
  other_interfaces.contact.pop_back();
  EXPECT_THROW(file.append_step(other_interfaces, x, nullptr), InputError);
  file.append_step(s, x, nullptr);
  try {
    file.append_step(s, x, nullptr);
    FAIL() << "a step written twice was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("step 1: steps must come in increasing order"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(read_results_summary(path).num_steps, 1) << "the refused steps left no trace";
  EXPECT_THROW(ResultsFile(dir_ / "no_such_dir" / "x.h5", f_.mesh, f_.depth, f_.info), InputError);
  for (const char* sidecar : {"x.xmf", "x.xdmf2"})
    EXPECT_THROW(ResultsFile(dir_ / sidecar, f_.mesh, f_.depth, f_.info), InputError) << sidecar;

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

// A second writer of the same file is refused before it touches the file.
TEST_F(ResultsFileTest, SecondWriterIsRefused) {
  const fs::path path = dir_ / "twice.h5";
  ResultsFile first(path, f_.mesh, f_.depth, f_.info);
  first.append_step(step_record(1), positions(f_.mesh, 1), nullptr);
  try {
    ResultsFile second(path, f_.mesh, f_.depth, f_.info);
    FAIL() << "a second writer was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is being written by another depthfem run"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(read_results_summary(path).num_steps, 1);
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
                     "has no dataset /steps/stress");
  expect_input_error([&] { read_step_dataset(run, 4, "x"); }, run, "has no step 4 (steps 1 to 1)");
  expect_input_error([&] { read_step_state(run, 0); }, run, "has no step 0");
}

// Damaged and foreign results files. Each is a valid file of two steps written by ResultsFile, then
// altered through the HDF5 C API (a dataset replaced by one of another shape, type or value) or by
// flipping a byte; every reader must end in one InputError line that starts with the file and
// names the dataset at fault, and none may wait on retries (a test that hangs is a failure:
// ctest's timeout).
class DamagedResultsTest : public ResultsFileTest {
 protected:
  // A valid results file of f_.mesh with steps 1 and 2, at `name` in the test's folder.
  fs::path valid(const std::string& name) const {
    const fs::path path = dir_ / name;
    ResultsFile file(path, f_.mesh, f_.depth, f_.info);
    for (int k = 1; k <= 2; ++k) file.append_step(step_record(k), positions(f_.mesh, k), nullptr);
    file.write_timing({{"solve", 1.5}});
    file.finish(true, "");
    return path;
  }

  // Replaces dataset `name` of the file at `path` by one of `dims` (none: a scalar) values of
  // `type` in the file, written from `values` (doubles, converted by HDF5; none: left unwritten).
  static void replace(const fs::path& path, const std::string& name, hid_t type,
                      const std::vector<hsize_t>& dims, const std::vector<double>& values = {}) {
    const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(access, false, true);
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, access);
    ASSERT_GE(file, 0) << path;
    ASSERT_GE(H5Ldelete(file, name.c_str(), H5P_DEFAULT), 0) << name;
    const hid_t space = dims.empty() ? H5Screate(H5S_SCALAR)
                                     : H5Screate_simple(int(dims.size()), dims.data(), nullptr);
    const hid_t set =
        H5Dcreate2(file, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(set, 0) << name;
    if (!values.empty()) {
      EXPECT_GE(H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    }
    H5Dclose(set);
    H5Sclose(space);
    H5Fclose(file);
    H5Pclose(access);
  }

  // Replaces attribute `name` of /run by `count` 32-bit integers.
  static void replace_run_attribute(const fs::path& path, const char* name, hsize_t count) {
    const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(access, false, true);
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, access);
    ASSERT_GE(file, 0) << path;
    ASSERT_GE(H5Adelete_by_name(file, "/run", name, H5P_DEFAULT), 0) << name;
    const hid_t space = H5Screate_simple(1, &count, nullptr);
    const hid_t attr = H5Acreate_by_name(file, "/run", name, H5T_STD_I32LE, space, H5P_DEFAULT,
                                         H5P_DEFAULT, H5P_DEFAULT);
    const std::vector<std::int32_t> values(count, 7);
    EXPECT_GE(H5Awrite(attr, H5T_NATIVE_INT32, values.data()), 0);
    H5Aclose(attr);
    H5Sclose(space);
    H5Fclose(file);
    H5Pclose(access);
  }

  // Flips every bit of the byte at `offset` of the file at `path`.
  static void flip(const fs::path& path, std::streamoff offset) {
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    file.seekg(offset);
    const char byte = char(file.get() ^ 0xff);
    file.seekp(offset);
    file.put(byte);
    ASSERT_TRUE(file.good()) << path;
  }

  // Runs `read`, which must throw one InputError line that starts with "PATH: " and names
  // `dataset`.
  template <class Read>
  static void expect_error(const Read& read, const fs::path& path, const std::string& dataset) {
    try {
      read();
      ADD_FAILURE() << "no InputError for " << dataset << " of " << path;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
      EXPECT_NE(message.find(dataset), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }

  // Every reader that reads `dataset` fails on the file at `path`, naming it.
  void expect_every_reader_fails(const fs::path& path, const std::string& dataset,
                                 bool summary = true) const {
    SCOPED_TRACE(dataset);
    if (summary) expect_error([&] { read_results_summary(path); }, path, dataset);
    expect_error([&] { read_step_state(path); }, path, dataset);
    expect_error([&] { read_step_dataset(path, 2, "x"); }, path, dataset);
  }
};

TEST_F(DamagedResultsTest, ValidFileReadsBack) {
  const fs::path path = valid("valid.h5");
  EXPECT_EQ(read_results_summary(path).num_steps, 2);
  EXPECT_EQ(read_step_state(path).x, positions(f_.mesh, 2));
  EXPECT_EQ(read_step_dataset(path, 2, "residuals"),
            Eigen::Map<const VectorX>(step_record(2).residuals.data(), 4));
  check_results_mesh(path, f_.mesh);
}

// HDF5's SWMR reader retries a metadata read whose checksum fails with sleeps that double each
// time, by default 100 times: a flipped byte of the superblock (48 bytes, all under its checksum)
// used to make every reader sleep forever. Now each fails at once.
TEST_F(DamagedResultsTest, FlippedSuperblockByteFailsAtOnce) {
  for (const std::streamoff offset : {12, 20, 28, 36, 40, 44}) {
    SCOPED_TRACE("superblock byte " + std::to_string(offset));
    const fs::path path = valid("superblock" + std::to_string(offset) + ".h5");
    flip(path, offset);
    expect_error([&] { read_results_summary(path); }, path, "HDF5");
    expect_error([&] { read_step_state(path); }, path, "HDF5");
    expect_error([&] { check_results_mesh(path, f_.mesh); }, path, "HDF5");
  }
}

// 300 bytes flipped one at a time anywhere in the file: each read ends in its values or in one
// error line naming the file, never in a crash or a wait.
TEST_F(DamagedResultsTest, RandomByteFlipsEndInValuesOrOneErrorLine) {
  const fs::path original = valid("original.h5"), path = dir_ / "flipped.h5";
  const std::uintmax_t size = fs::file_size(original);
  std::mt19937 random(29);
  int refused = 0;
  for (int k = 0; k < 300; ++k) {
    fs::copy_file(original, path, fs::copy_options::overwrite_existing);
    const std::streamoff offset = std::streamoff(random() % size);
    flip(path, offset);
    for (int reader = 0; reader < 3; ++reader) {
      try {
        if (reader == 0) read_results_summary(path);
        if (reader == 1) read_step_state(path);
        if (reader == 2) check_results_mesh(path, f_.mesh);
      } catch (const InputError& e) {
        ++refused;
        const std::string message = e.what();
        EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u)
            << "byte " << offset << ": " << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      }
    }
  }
  EXPECT_GT(refused, 0) << "no flipped byte was noticed: the test cannot fail";
}

// A variable-length string is a reference into a heap collection of the file (its address and an
// object index) and HDF5 1.10 checks neither the index nor the collection's object sizes
// (H5HG_read, H5HG__cache_heap_deserialize), so that a damaged one crashed the reader (found by
// tests/fuzz/fuzz_results). The references of a dataset are checked before HDF5 reads them; the
// strings of attributes, whose references HDF5 does not show, are decoded in a child process.
TEST_F(DamagedResultsTest, DamagedStringHeapIsNamed) {
  // Each string of /mesh/body_names: its length (4 bytes), its heap collection's address (8),
  // its object's index (4).
  const auto names_at = [](const fs::path& path) {
    const RawFile raw(path);
    return raw.offset("/mesh/body_names");
  };
  const auto bytes_at = [](const fs::path& path, std::streamoff at, int count) {
    std::ifstream file(path, std::ios::binary);
    file.seekg(at);
    std::uint64_t out = 0;
    for (int k = 0; k < count; ++k) out |= std::uint64_t(std::uint8_t(file.get())) << (8 * k);
    return out;
  };
  {
    const fs::path path = valid("string_index.h5");
    const haddr_t names = names_at(path);
    ASSERT_NE(names, HADDR_UNDEF);
    flip(path, std::streamoff(names + 4 + 8 + 1));
    expect_error([&] { read_results_summary(path); }, path, "/mesh/body_names");
  }
  {
    // The collection: "GCOL", version, 3 bytes, size (8), then objects: index (2), references
    // (2), 4 bytes, size (8), data padded to 8 bytes. The object holding "static" (/run attribute
    // analysis) gets a size of 2^40 + 6.
    const fs::path path = valid("string_heap.h5");
    const haddr_t names = names_at(path);
    ASSERT_NE(names, HADDR_UNDEF);
    const std::streamoff heap = std::streamoff(bytes_at(path, std::streamoff(names + 4), 8));
    const std::uint64_t size = bytes_at(path, heap + 8, 8);
    std::streamoff analysis = 0;
    for (std::streamoff at = heap + 16; at + 16 <= heap + std::streamoff(size);) {
      const std::uint64_t bytes = bytes_at(path, at + 8, 8);
      if (bytes == 6 && bytes_at(path, at + 16, 6) == 0x636974617473)  // "static", little-endian
        analysis = at;
      at += 16 + std::streamoff((bytes + 7) / 8 * 8);
    }
    ASSERT_NE(analysis, 0) << "no heap object \"static\"";
    flip(path, analysis + 8 + 5);  // byte 5 of its size: 2^40 more
    expect_error([&] { read_results_summary(path); }, path, "/mesh/body_names");
    expect_error([&] { H5File::open(path.string()).string_attribute("/run", "analysis"); }, path,
                 "attribute analysis");
  }
}

// The shapes and types of the examples that crashed or misbehaved: /steps/load of shape (#steps,
// 0) (a read past an empty vector), a scalar /mesh/X and an empty /run/status (range checks that
// threw std::out_of_range, an unlocated message), and others like them.
TEST_F(DamagedResultsTest, DatasetsOfAnotherShapeOrTypeAreNamed) {
  const hid_t f64 = H5T_IEEE_F64LE, i32 = H5T_STD_I32LE;
  {
    const fs::path path = valid("load_n_by_0.h5");
    replace(path, "/steps/load", f64, {2, 0});
    expect_error([&] { read_results_summary(path); }, path, "/steps/load");
    expect_error([&] { read_step_state(path); }, path, "/steps/load");
  }
  {
    const fs::path path = valid("scalar_X.h5");
    replace(path, "/mesh/X", f64, {}, {1.0});
    expect_error([&] { read_results_summary(path); }, path, "/mesh/X");
    expect_error([&] { read_step_state(path); }, path, "/mesh/X");
    expect_error([&] { check_results_mesh(path, f_.mesh); }, path, "/mesh/X");
  }
  {
    const fs::path path = valid("empty_status.h5");
    const hid_t text = H5Tcopy(H5T_C_S1);
    H5Tset_size(text, 16);
    replace(path, "/run/status", text, {0});
    H5Tclose(text);
    expect_error([&] { read_results_summary(path); }, path, "/run/status");
  }
  {
    const fs::path path = valid("X_as_integers.h5");
    replace(path, "/mesh/X", i32, {12, 3}, std::vector<double>(36, 0.0));
    expect_error([&] { read_results_summary(path); }, path, "/mesh/X");
  }
  {
    const fs::path path = valid("x_of_another_mesh.h5");
    replace(path, "/steps/x", f64, {2, 11, 3}, std::vector<double>(66, 0.0));
    expect_error([&] { read_step_state(path); }, path, "/steps/x");
  }
  {
    const fs::path path = valid("tets_of_3.h5");
    replace(path, "/mesh/tets", i32, {12, 3}, std::vector<double>(36, 0.0));
    expect_error([&] { read_results_summary(path); }, path, "/mesh/tets");
    expect_error([&] { check_results_mesh(path, f_.mesh); }, path, "/mesh/tets");
  }
  {
    const fs::path path = valid("huge_rows.h5");
    // Never written, so it takes no space: 2^43 values that a reader must not allocate.
    replace(path, "/steps/displacement", f64, {2, hsize_t(1) << 40, 3});
    expect_error([&] { read_step_dataset(path, 1, "displacement"); }, path, "/steps/displacement");
  }
  for (const char* attribute : {"threads", "analysis"}) {
    // H5Aread writes every value an attribute holds into the one value it is given.
    const fs::path path = valid(std::string("attribute_") + attribute + ".h5");
    replace_run_attribute(path, attribute, 1000);
    expect_error([&] { read_results_summary(path); }, path, attribute);
  }
}

// Values a writer cannot have written: a step index that is NaN, 1e300 or beyond the int range
// (a conversion to Index that was undefined behaviour), out of order; non-finite loads and
// positions; iteration and residual counts that are not counts.
TEST_F(DamagedResultsTest, ValuesOutOfRangeAreNamed) {
  const hid_t f64 = H5T_IEEE_F64LE, i32 = H5T_STD_I32LE, i64 = H5T_STD_I64LE;
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  int k = 0;  // numbers the files
  for (const double index : {nan, 1e300}) {
    const fs::path path = valid("index_f64_" + std::to_string(++k) + ".h5");
    replace(path, "/steps/index", f64, {2}, {1, index});
    expect_every_reader_fails(path, "/steps/index");
  }
  for (const double index : {double(hsize_t(1) << 40), -3.0}) {
    const fs::path path = valid("index_i64_" + std::to_string(++k) + ".h5");
    replace(path, "/steps/index", i64, {2}, {1, index});
    expect_every_reader_fails(path, "/steps/index", false);  // the summary counts its rows only
  }
  {
    const fs::path path = valid("index_decreasing.h5");
    replace(path, "/steps/index", i32, {2}, {2, 1});
    expect_every_reader_fails(path, "/steps/index", false);
  }
  for (const double load : {nan, inf}) {
    const fs::path path = valid("load_" + std::to_string(++k) + ".h5");
    replace(path, "/steps/load", f64, {2}, {0.5, load});
    expect_error([&] { read_results_summary(path); }, path, "/steps/load");
    expect_error([&] { read_step_state(path); }, path, "/steps/load");
  }
  {
    const fs::path path = valid("x_nan.h5");
    std::vector<double> x(2 * 12 * 3, 0.5);
    x[12 * 3 + 7] = nan;
    replace(path, "/steps/x", f64, {2, 12, 3}, x);
    expect_error([&] { read_step_state(path); }, path, "/steps/x");
    // The dataset reader gives the values as written: NaN is what a step reports without a
    // penetration.
    EXPECT_TRUE(std::isnan(read_step_dataset(path, 2, "x")(2, 1)));
  }
  for (const double count : {-1.0, double(hsize_t(1) << 40)}) {
    const fs::path path = valid("iterations_" + std::to_string(++k) + ".h5");
    replace(path, "/steps/newton_iterations", i64, {2}, {3, count});
    expect_error([&] { read_results_summary(path); }, path, "/steps/newton_iterations");
  }
  {
    const fs::path path = valid("residual_count.h5");
    replace(path, "/steps/residual_count", i64, {2}, {3, double(hsize_t(1) << 40)});
    expect_error([&] { read_step_dataset(path, 2, "residuals"); }, path, "/steps/residual_count");
  }
  {
    const fs::path path = valid("seconds.h5");
    replace(path, "/timing/seconds", f64, {1}, {-2});
    expect_error([&] { read_results_summary(path); }, path, "/timing/seconds");
  }
}

// A results file belongs to a mesh by its nodes and tets, not by their counts: a run of another
// scene with as many nodes and tets is refused, naming the dataset that differs; the same mesh
// a few units in the last place apart (another build) is accepted.
TEST_F(DamagedResultsTest, FileOfAnotherMeshWithTheSameCountsIsRefused) {
  const fs::path path = valid("run.h5");
  check_results_mesh(path, f_.mesh);
  Mesh rounded = f_.mesh;
  rounded.X *= 1 + 4 * std::numeric_limits<double>::epsilon();
  check_results_mesh(path, rounded);

  const Mesh moved = single_body_mesh(
      box_mesh({Vec3(0.1, -0.2, 0.3), Vec3(0.4, 0.3, 0.8), Eigen::Vector3i(1, 1, 2)}), "block");
  ASSERT_EQ(moved.num_nodes(), f_.mesh.num_nodes());
  ASSERT_EQ(moved.num_tets(), f_.mesh.num_tets());
  expect_error([&] { check_results_mesh(path, moved); }, path, "/mesh/X");

  Mesh renumbered = f_.mesh;
  renumbered.tets.row(3).swap(renumbered.tets.row(5));
  expect_error([&] { check_results_mesh(path, renumbered); }, path, "/mesh/tets");

  const Mesh finer = single_body_mesh(
      box_mesh({Vec3(0.1, -0.2, 0.3), Vec3(0.4, 0.3, 0.7), Eigen::Vector3i(1, 2, 2)}), "block");
  expect_error([&] { check_results_mesh(path, finer); }, path, "/mesh/X and /mesh/tets");
}

}  // namespace
}  // namespace depthfem
