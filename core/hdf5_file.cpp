#include "core/hdf5_file.hpp"

#include <filesystem>

#include "core/error.hpp"

namespace depthfem {

namespace {

/// Copies a variable-length string that HDF5 allocated, then frees it (null reads as "").
std::string take_string(char* value) {
  std::string out = value ? value : "";
  H5free_memory(value);
  return out;
}

/// File access without HDF5's file locks, for writing and reading alike: a running simulation's
/// results file stays readable by other processes (h5py, ParaView, `depthfem info`) between
/// steps, and HDF5 refuses to reopen an open file with a different locking setting. Also turns
/// HDF5's printing of error stacks off: failures become exceptions instead.
Handle unlocked_access(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (access.id() < 0 || H5Pset_file_locking(access.id(), false, true) < 0)
    throw InputError(located(path, 0, "cannot set up HDF5 file access"));
  return access;
}

}  // namespace

H5File H5File::create(const std::string& path) {
  const Handle access = unlocked_access(path);
  return H5File(path, H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.id()),
                "cannot create results file");
}

H5File H5File::open(const std::string& path) {
  const Handle access = unlocked_access(path);
  if (!std::filesystem::exists(path)) throw InputError(located(path, 0, "no such results file"));
  return H5File(path, H5Fopen(path.c_str(), H5F_ACC_RDONLY, access.id()),
                "cannot be opened as an HDF5 file");
}

H5File::H5File(std::string path, hid_t id, const char* failure)
    : path_(std::move(path)), file_(id, H5Fclose) {
  if (id < 0) fail(failure);
}

void H5File::fail(const std::string& what) const {
  throw InputError(located(path_, 0, what));
}

void H5File::flush() const {
  check(H5Fflush(file_.id(), H5F_SCOPE_GLOBAL), "cannot flush");
}

void H5File::create_group(const std::string& name) const {
  const std::string what = "cannot create group " + name;
  const Handle properties = handle(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, what);
  check(H5Pset_attr_creation_order(properties.id(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED),
        what);
  handle(H5Gcreate2(file_.id(), name.c_str(), H5P_DEFAULT, properties.id(), H5P_DEFAULT), H5Gclose,
         what);
}

void H5File::remove(const std::string& name) const {
  check(H5Ldelete(file_.id(), name.c_str(), H5P_DEFAULT), "cannot remove " + name);
}

void H5File::write_strings(const std::string& name, const std::vector<std::string>& values) const {
  std::vector<const char*> pointers;
  for (const std::string& value : values) pointers.push_back(value.c_str());
  const Handle type = string_type("cannot write " + name);
  write_raw(name, type.id(), type.id(), {hsize_t(values.size())}, pointers.data());
}

void H5File::set_string_attribute(const std::string& object, const std::string& name,
                                  const std::string& value) const {
  const Handle type = string_type("cannot write attribute " + name + " of " + object);
  const char* pointer = value.c_str();
  write_attribute(object, name, type.id(), type.id(), &pointer);
}

bool H5File::exists(const std::string& name) const {
  return H5Lexists(file_.id(), name.c_str(), H5P_DEFAULT) > 0;
}

std::vector<hsize_t> H5File::dims(const std::string& name) const {
  const std::string what = "cannot read " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const Handle space = handle(H5Dget_space(set.id()), H5Sclose, what);
  std::vector<hsize_t> out(check(H5Sget_simple_extent_ndims(space.id()), what));
  check(H5Sget_simple_extent_dims(space.id(), out.data(), nullptr), what);
  return out;
}

std::vector<double> H5File::read_doubles(const std::string& name) const {
  const std::string what = "cannot read " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const Handle space = handle(H5Dget_space(set.id()), H5Sclose, what);
  std::vector<double> out(check(H5Sget_simple_extent_npoints(space.id()), what));
  if (!out.empty())
    check(H5Dread(set.id(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), what);
  return out;
}

std::vector<std::string> H5File::read_strings(const std::string& name) const {
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

std::string H5File::string_attribute(const std::string& object, const std::string& name) const {
  const std::string what = "cannot read attribute " + name + " of " + object;
  const Handle attr = open_attribute(object, name, what);
  const Handle type = string_type(what);
  char* value = nullptr;
  check(H5Aread(attr.id(), type.id(), &value), what);
  return take_string(value);
}

std::vector<std::string> H5File::link_names(const std::string& group) const {
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

std::vector<std::string> H5File::attribute_names(const std::string& object) const {
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

Handle H5File::handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) const {
  return Handle(check(id, what), close);
}

Handle H5File::string_type(const std::string& what) const {
  Handle type = handle(H5Tcopy(H5T_C_S1), H5Tclose, what);
  check(H5Tset_size(type.id(), H5T_VARIABLE), what);
  check(H5Tset_cset(type.id(), H5T_CSET_UTF8), what);
  return type;
}

void H5File::write_raw(const std::string& name, hid_t file_type, hid_t memory_type,
                       const std::vector<hsize_t>& dims, const void* data) const {
  const std::string what = "cannot write " + name;
  const Handle space =
      handle(H5Screate_simple(int(dims.size()), dims.data(), nullptr), H5Sclose, what);
  const Handle set = handle(H5Dcreate2(file_.id(), name.c_str(), file_type, space.id(), H5P_DEFAULT,
                                       H5P_DEFAULT, H5P_DEFAULT),
                            H5Dclose, what);
  // An empty dataset needs no write (and HDF5 rejects the null buffer of an empty array).
  if (check(H5Sget_simple_extent_npoints(space.id()), what) > 0)
    check(H5Dwrite(set.id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), what);
}

void H5File::write_attribute(const std::string& object, const std::string& name, hid_t file_type,
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

Handle H5File::open_attribute(const std::string& object, const std::string& name,
                              const std::string& what) const {
  return handle(H5Aopen_by_name(file_.id(), object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
                H5Aclose, what);
}

}  // namespace depthfem
