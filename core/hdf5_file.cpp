#include "core/hdf5_file.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
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
/// HDF5's printing of error stacks off: failures become exceptions instead, and its clean-up at
/// exit too: every file is closed by its H5File, and the clean-up crashes (HDF5 1.10) on a file
/// whose close failed on a write error (a full disk, a file-size limit).
Handle unlocked_access(const std::string& path) {
  H5dont_atexit();  // takes effect only before the library's first call; harmless after
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (access.id() < 0 || H5Pset_file_locking(access.id(), false, true) < 0)
    throw InputError(located(path, 0, "cannot set up HDF5 file access"));
  return access;
}

}  // namespace

H5File H5File::create(const std::string& path, const std::string& name) {
  const Handle access = unlocked_access(name);
  // SWMR writing needs the 1.10 file format (its chunk indices and checksummed metadata).
  if (H5Pset_libver_bounds(access.id(), H5F_LIBVER_V110, H5F_LIBVER_V110) < 0)
    throw InputError(located(name, 0, "cannot set up HDF5 file access"));
  // A flush visits every entry of HDF5's metadata cache, which by default grows to megabytes
  // over a long run, so flushing after every step would cost more and more. A fixed cache of
  // 256 KiB keeps the cost per step flat (bench/bench_results_file.cpp, BM_LongRun).
  H5AC_cache_config_t cache;
  cache.version = H5AC__CURR_CACHE_CONFIG_VERSION;
  if (H5Pget_mdc_config(access.id(), &cache) < 0)
    throw InputError(located(name, 0, "cannot set up HDF5 file access"));
  cache.set_initial_size = true;
  cache.initial_size = cache.max_size = 256 * 1024;
  cache.min_size = 128 * 1024;
  cache.incr_mode = H5C_incr__off;
  cache.flash_incr_mode = H5C_flash_incr__off;
  cache.decr_mode = H5C_decr__off;
  if (H5Pset_mdc_config(access.id(), &cache) < 0)
    throw InputError(located(name, 0, "cannot set up HDF5 file access"));
  return H5File(path, name, H5Fcreate(path.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, access.id()),
                "cannot create results file");
}

H5File H5File::open(const std::string& path) {
  const Handle access = unlocked_access(path);
  // A SWMR reader may catch the writer in the middle of writing an object, so HDF5 reads
  // metadata whose checksum fails again, sleeping 1, 2, 4, ... ns between tries: n tries wait
  // 2^n ns in all. Its default of 100 tries waits forever on a damaged file; 20 wait about 1 ms,
  // with which every live read of apps/tools/kill_test.sh still succeeds.
  if (H5Pset_metadata_read_attempts(access.id(), kMetadataReadAttempts) < 0)
    throw InputError(located(path, 0, "cannot set up HDF5 file access"));
  if (!std::filesystem::exists(path)) throw InputError(located(path, 0, "no such results file"));
  return H5File(path, path, H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, access.id()),
                "cannot be opened as an HDF5 file (not one, or its superblock is damaged)");
}

void H5File::rename(const std::string& path) {
  std::error_code error;
  std::filesystem::rename(path_, path, error);
  if (error) fail("cannot be renamed to " + path + ": " + error.message());
  path_ = name_ = path;
}

void H5File::start_swmr_write() const {
  check(H5Fstart_swmr_write(file_.id()), "cannot start single-writer/multiple-reader mode");
}

H5File::H5File(std::string path, std::string name, hid_t id, const char* failure)
    : path_(std::move(path)), name_(std::move(name)), file_(id, H5Fclose) {
  if (id < 0) fail(failure);
}

void H5File::fail(const std::string& what) const {
  throw InputError(located(name_, 0, what));
}

void H5File::flush() const {
  check(H5Fflush(file_.id(), H5F_SCOPE_GLOBAL), "cannot flush");
}

H5File::Reservation H5File::reserve(hsize_t bytes) const {
  const auto [end, descriptor] = end_and_descriptor("cannot reserve disk space");
  const int error = posix_fallocate(descriptor, end, off_t(bytes));
  if (error != 0) {
    give_back();  // what the failed allocation may have added
    fail("no room for " + std::to_string(bytes / 1024) + " KiB more (" + std::strerror(error) +
         ")");
  }
  return Reservation(*this);
}

void H5File::give_back() const noexcept {
  try {
    const auto [end, descriptor] = end_and_descriptor("");
    struct stat status {};
    if (fstat(descriptor, &status) == 0 && status.st_size > end) (void)!ftruncate(descriptor, end);
  } catch (const InputError&) {
  }
}

std::pair<off_t, int> H5File::end_and_descriptor(const std::string& what) const {
  haddr_t end = 0;
  void* handle = nullptr;
  check(H5Fget_eoa(file_.id(), &end), what);
  check(H5Fget_vfd_handle(file_.id(), H5P_DEFAULT, &handle), what);
  return {off_t(end), *static_cast<const int*>(handle)};
}

void H5File::create_group(const std::string& name) const {
  const std::string what = "cannot create group " + name;
  const Handle properties = handle(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, what);
  check(H5Pset_attr_creation_order(properties.id(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED),
        what);
  handle(H5Gcreate2(file_.id(), name.c_str(), H5P_DEFAULT, properties.id(), H5P_DEFAULT), H5Gclose,
         what);
}

void H5File::create_rows(const std::string& name, hid_t type,
                         const std::vector<hsize_t>& row_dims) const {
  const std::string what = "cannot create " + name;
  std::vector<hsize_t> dims{0}, max_dims{H5S_UNLIMITED}, chunk{1};
  hsize_t row_bytes = check(hsize_t(H5Tget_size(type)), what);
  for (const hsize_t d : row_dims) {
    dims.push_back(d);
    // A chunk dimension must be positive and, where the dataset cannot grow, within its size.
    max_dims.push_back(d == 0 ? H5S_UNLIMITED : d);
    chunk.push_back(std::max<hsize_t>(d, 1));
    row_bytes *= std::max<hsize_t>(d, 1);
  }
  chunk[0] = std::max<hsize_t>(1, 4096 / row_bytes);
  const Handle space =
      handle(H5Screate_simple(int(dims.size()), dims.data(), max_dims.data()), H5Sclose, what);
  const Handle properties = handle(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, what);
  check(H5Pset_chunk(properties.id(), int(chunk.size()), chunk.data()), what);
  handle(H5Dcreate2(file_.id(), name.c_str(), type, space.id(), H5P_DEFAULT, properties.id(),
                    H5P_DEFAULT),
         H5Dclose, what);
}

void H5File::write_rows(const std::string& name, hsize_t first, hsize_t count, hid_t memory_type,
                        const void* data) const {
  const std::string what = "cannot write " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  std::vector<hsize_t> dims = dataset_dims(set.id(), what);
  if (dims[0] < first + count) {
    dims[0] = first + count;
    check(H5Dset_extent(set.id(), dims.data()), what);
  }
  const RowSelection rows = select_rows(set.id(), first, count, what);
  if (rows.values > 0)
    check(H5Dwrite(set.id(), memory_type, rows.memory.id(), rows.file.id(), H5P_DEFAULT, data),
          what);
}

void H5File::set_rows(const std::string& name, hsize_t rows) const {
  const std::string what = "cannot resize " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  std::vector<hsize_t> dims = dataset_dims(set.id(), what);
  dims[0] = rows;
  check(H5Dset_extent(set.id(), dims.data()), what);
}

std::vector<double> H5File::read_rows(const std::string& name, hsize_t first, hsize_t count) const {
  const std::string what = "cannot read " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const std::vector<hsize_t> dims = dataset_dims(set.id(), what);
  if (dims.empty() || count > dims[0] || first > dims[0] - count)
    fail(what + ": rows " + std::to_string(first) + " to " + std::to_string(first + count) +
         " asked of " + std::to_string(dims.empty() ? 0 : dims[0]));
  const hsize_t values = fitting_values(dims, 1, count, stored_size(set.id(), what), what);
  const RowSelection rows = select_rows(set.id(), first, count, what);
  if (hsize_t(rows.values) != values) fail(what + ": a selection of rows that HDF5 miscounts");
  std::vector<double> out(values);
  if (!out.empty())
    check(H5Dread(set.id(), H5T_NATIVE_DOUBLE, rows.memory.id(), rows.file.id(), H5P_DEFAULT,
                  out.data()),
          what);
  return out;
}

void H5File::create_text(const std::string& name, size_t capacity) const {
  const std::string what = "cannot create " + name;
  const Handle type = fixed_string_type(capacity, what);
  const Handle space = handle(H5Screate(H5S_SCALAR), H5Sclose, what);
  // Storage allocated at creation: writing the text later changes no metadata.
  const Handle properties = handle(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, what);
  check(H5Pset_layout(properties.id(), H5D_CONTIGUOUS), what);
  check(H5Pset_alloc_time(properties.id(), H5D_ALLOC_TIME_EARLY), what);
  handle(H5Dcreate2(file_.id(), name.c_str(), type.id(), space.id(), H5P_DEFAULT, properties.id(),
                    H5P_DEFAULT),
         H5Dclose, what);
}

void H5File::write_text(const std::string& name, const std::string& value) const {
  const std::string what = "cannot write " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const Handle type = handle(H5Dget_type(set.id()), H5Tclose, what);
  std::string buffer = value;
  buffer.resize(check(H5Tget_size(type.id()), what), '\0');
  check(H5Dwrite(set.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()), what);
}

void H5File::create_text_rows(const std::string& name, size_t capacity) const {
  const Handle type = fixed_string_type(capacity, "cannot create " + name);
  create_rows(name, type.id(), {});
}

void H5File::write_text_rows(const std::string& name,
                             const std::vector<std::string>& values) const {
  const std::string what = "cannot write " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const Handle type = handle(H5Dget_type(set.id()), H5Tclose, what);
  const size_t capacity = check(H5Tget_size(type.id()), what);
  std::string buffer;
  for (const std::string& value : values)
    buffer += (value + std::string(capacity, '\0')).substr(0, capacity);
  set_rows(name, values.size());
  write_rows(name, 0, values.size(), type.id(), buffer.data());
}

std::vector<std::string> H5File::read_texts(const std::string& name) const {
  const std::string what = "cannot read " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const Handle type = handle(H5Dget_type(set.id()), H5Tclose, what);
  if (H5Tget_class(type.id()) != H5T_STRING || H5Tis_variable_str(type.id()) != 0)
    fail(what + ": not a dataset of fixed-length strings");
  const size_t capacity = check(H5Tget_size(type.id()), what);
  const hssize_t count = hssize_t(
      fitting_values(dataset_dims(set.id(), what), 0, 1, std::max<size_t>(capacity, 1), what));
  std::string buffer(size_t(count) * capacity, '\0');
  if (count > 0)
    check(H5Dread(set.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()), what);
  std::vector<std::string> out;
  for (hssize_t k = 0; k < count; ++k) {
    const std::string text = buffer.substr(size_t(k) * capacity, capacity);
    out.push_back(text.substr(0, text.find('\0')));
  }
  return out;
}

void H5File::create_zeros(const std::string& name, const std::vector<hsize_t>& dims) const {
  const std::string what = "cannot write " + name;
  const Handle space =
      handle(H5Screate_simple(int(dims.size()), dims.data(), nullptr), H5Sclose, what);
  handle(H5Dcreate2(file_.id(), name.c_str(), H5Type<double>::file(), space.id(), H5P_DEFAULT,
                    H5P_DEFAULT, H5P_DEFAULT),
         H5Dclose, what);
}

void H5File::create_row_view(const std::string& name, const std::string& source, hsize_t first_row,
                             hsize_t num_rows) const {
  const std::string what = "cannot write " + name + " (a view of " + source + ")";
  const Handle source_set =
      handle(H5Dopen2(file_.id(), source.c_str(), H5P_DEFAULT), H5Dclose, what);
  const Handle source_space = handle(H5Dget_space(source_set.id()), H5Sclose, what);
  const Handle type = handle(H5Dget_type(source_set.id()), H5Tclose, what);
  std::vector<hsize_t> dims(check(H5Sget_simple_extent_ndims(source_space.id()), what));
  check(H5Sget_simple_extent_dims(source_space.id(), dims.data(), nullptr), what);
  if (dims.empty() || first_row + num_rows > dims[0]) fail(what + ": rows out of range");
  std::vector<hsize_t> start(dims.size(), 0), count = dims;
  start[0] = first_row;
  count[0] = num_rows;
  check(H5Sselect_hyperslab(source_space.id(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                            nullptr),
        what);
  const Handle view_space =
      handle(H5Screate_simple(int(count.size()), count.data(), nullptr), H5Sclose, what);
  const Handle properties = handle(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, what);
  // "." is this file, so that the view follows the file when it is renamed or moved.
  check(H5Pset_virtual(properties.id(), view_space.id(), ".", source.c_str(), source_space.id()),
        what);
  handle(H5Dcreate2(file_.id(), name.c_str(), type.id(), view_space.id(), H5P_DEFAULT,
                    properties.id(), H5P_DEFAULT),
         H5Dclose, what);
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
  return dataset_dims(set.id(), what);
}

H5T_class_t H5File::type_class(const std::string& name) const {
  const std::string what = "cannot read " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const Handle type = handle(H5Dget_type(set.id()), H5Tclose, what);
  const H5T_class_t out = H5Tget_class(type.id());
  if (out == H5T_NO_CLASS) fail(what);
  return out;
}

std::vector<double> H5File::read_doubles(const std::string& name) const {
  const std::string what = "cannot read " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  std::vector<double> out(
      fitting_values(dataset_dims(set.id(), what), 0, 1, stored_size(set.id(), what), what));
  if (!out.empty())
    check(H5Dread(set.id(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), what);
  return out;
}

std::vector<std::string> H5File::read_strings(const std::string& name) const {
  const std::string what = "cannot read " + name;
  const Handle set = handle(H5Dopen2(file_.id(), name.c_str(), H5P_DEFAULT), H5Dclose, what);
  const std::vector<hsize_t> dims = dataset_dims(set.id(), what);
  if (dims.size() != 1) fail(what + ": not a list of strings");
  {
    const Handle file_type = handle(H5Dget_type(set.id()), H5Tclose, what);
    if (H5Tget_class(file_type.id()) != H5T_STRING || H5Tis_variable_str(file_type.id()) <= 0)
      fail(what + ": not a dataset of variable-length strings");
  }
  // A variable-length string takes 16 bytes in the file (a reference into a heap).
  const hsize_t count = fitting_values(dims, 0, 1, 16, what);
  check_string_references(set.id(), count, what);
  std::vector<char*> raw(count, nullptr);
  const Handle type = string_type(what);
  if (!raw.empty())
    check(H5Dread(set.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()), what);
  std::vector<std::string> out;
  for (char* value : raw) out.push_back(take_string(value));
  return out;
}

std::string H5File::string_attribute(const std::string& object, const std::string& name) const {
  return string_attributes(object, {name}).at(0);
}

std::vector<std::string> H5File::string_attributes(const std::string& object,
                                                   const std::vector<std::string>& names) const {
  std::vector<Handle> attributes;
  std::string what;
  for (const std::string& name : names) {
    what = "cannot read attribute " + name + " of " + object;
    attributes.push_back(open_attribute(object, name, what));
    check_one_value(attributes.back().id(), true, what);
  }
  // HDF5 1.10 trusts the heap collection that holds the strings (H5HG_read indexes its objects
  // unchecked; a damaged object size makes it read or loop out of bounds), and no function of
  // its API gives an attribute's reference into it to check first: they are decoded in a child
  // process, where such damage ends the child, not the reader.
  const std::string of = names.size() == 1 ? what : "cannot read the attributes of " + object;
  return decode_strings(
      [&] {
        std::vector<std::string> out;
        const Handle type = string_type(of);
        for (const Handle& attribute : attributes) {
          char* value = nullptr;
          check(H5Aread(attribute.id(), type.id(), &value), of);
          out.push_back(take_string(value));
        }
        return out;
      },
      of);
}

namespace {

/// Little-endian unsigned integer of `bytes` bytes at `p`.
std::uint64_t little_endian(const unsigned char* p, int bytes) {
  std::uint64_t out = 0;
  for (int k = bytes - 1; k >= 0; --k) out = out << 8 | p[k];
  return out;
}

}  // namespace

void H5File::check_string_references(hid_t set, hsize_t count, const std::string& what) const {
  if (count == 0) return;
  // HDF5's file format (its specification, sections III.E and IV.B) with the 8-byte addresses
  // and lengths of depthfem's files: a string is its length (4 bytes), the address of a global
  // heap collection (8) and the index of an object in it (4). A collection is "GCOL", version 1,
  // 3 reserved bytes, its size (8; at least 4096), then objects: index (2), reference count (2),
  // 4 reserved bytes, size (8), data padded to 8 bytes; the free space is object 0, its size
  // including its 16 header bytes; less than 16 bytes at the end are free space too.
  const haddr_t data = H5Dget_offset(set);
  if (data == HADDR_UNDEF) fail(what + ": its strings are not stored as depthfem stores them");
  hsize_t base = 0;  // addresses count from the end of a user block
  {
    const Handle properties = handle(H5Fget_create_plist(file_.id()), H5Pclose, what);
    check(H5Pget_userblock(properties.id(), &base), what);
  }
  const int fd = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(what + ": " + std::strerror(errno));
  struct stat status {};
  const std::uint64_t file_bytes = fstat(fd, &status) == 0 ? std::uint64_t(status.st_size) : 0;
  // `bytes` bytes from `at`, or none when they do not all lie in the file.
  const auto read_at = [&](std::uint64_t at, std::uint64_t bytes) {
    if (at > file_bytes || bytes > file_bytes - at) return std::vector<unsigned char>();
    std::vector<unsigned char> out(bytes);
    size_t done = 0;
    while (done < bytes) {
      const ssize_t n = pread(fd, out.data() + done, bytes - done, off_t(at + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      done += size_t(n);
    }
    return done == bytes ? out : std::vector<unsigned char>();
  };
  std::string damage;
  const std::vector<unsigned char> references = read_at(data, count * 16);
  if (references.empty()) damage = "its strings lie beyond the end of the file";
  for (hsize_t k = 0; damage.empty() && k < count; ++k) {
    const unsigned char* reference = references.data() + 16 * k;
    const std::uint64_t length = little_endian(reference, 4),
                        collection = little_endian(reference + 4, 8),
                        index = little_endian(reference + 12, 4);
    if (collection == 0) continue;  // no heap object: HDF5 reads nothing
    const std::string which = "string " + std::to_string(k) + " ";
    const std::vector<unsigned char> header =
        collection < file_bytes ? read_at(base + collection, 16) : std::vector<unsigned char>();
    const std::uint64_t size = header.empty() ? 0 : little_endian(header.data() + 8, 8);
    const std::vector<unsigned char> heap =
        header.empty() || std::memcmp(header.data(), "GCOL\1", 5) != 0 || size < 4096
            ? std::vector<unsigned char>()
            : read_at(base + collection, size);
    if (heap.empty()) {
      damage = which + "names no heap collection in the file";
      break;
    }
    // The walk of HDF5's H5HG__cache_heap_deserialize, which checks nothing itself: each object
    // must end inside the collection (a free space of size 0 would make HDF5 loop for ever); of
    // several objects of one index HDF5 keeps the last.
    std::uint64_t found = ~std::uint64_t(0);
    for (std::uint64_t at = 16; damage.empty() && at + 16 <= size;) {
      const std::uint64_t object = little_endian(&heap[at], 2),
                          bytes = little_endian(&heap[at + 8], 8);
      const std::uint64_t need = bytes > size ? size + 1
                                 : object > 0 ? 16 + (bytes + 7) / 8 * 8
                                              : bytes;
      if (need < 16 || need > size - at) damage = which + "names a damaged heap collection";
      if (object == index) found = bytes;
      at += need;
    }
    if (damage.empty() && (index == 0 || found == ~std::uint64_t(0)))
      damage = which + "names no object of its heap collection";
    else if (damage.empty() && found != length)
      damage = which + "and its heap object differ in length";
  }
  ::close(fd);
  if (!damage.empty()) fail(what + ": " + damage);
}

std::vector<std::string> H5File::decode_strings(
    const std::function<std::vector<std::string>()>& decode, const std::string& what) const {
  // The child sends a kind (0: strings, 1: the message of an InputError), then each string as
  // its length (8 bytes) and bytes, and exits; the parent reads until the pipe closes.
  int pipe_ends[2];
  if (pipe(pipe_ends) != 0) return decode();  // no child to be had: decode here
  const pid_t child = fork();
  if (child < 0) {
    close(pipe_ends[0]);
    close(pipe_ends[1]);
    return decode();
  }
  if (child == 0) {
    close(pipe_ends[0]);
    // A crash is the parent's one error line: no handler, and no message of the child's own
    // (glibc's "double free", a sanitizer's report) on the reader's stderr.
    for (const int crash : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(crash, SIG_DFL);
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) dup2(null, STDERR_FILENO);
    std::string message(1, '\0');
    std::vector<std::string> strings;
    try {
      strings = decode();
    } catch (const InputError& e) {
      message[0] = 1;
      strings = {e.what()};
    }
    for (const std::string& text : strings) {
      const std::uint64_t length = text.size();
      message.append(reinterpret_cast<const char*>(&length), sizeof length).append(text);
    }
    for (size_t sent = 0; sent < message.size();) {
      const ssize_t n = write(pipe_ends[1], message.data() + sent, message.size() - sent);
      if (n < 0 && errno != EINTR) _exit(2);
      if (n > 0) sent += size_t(n);
    }
    _exit(0);  // no exit handlers: the parent's HDF5 files and buffers stay as they are
  }
  close(pipe_ends[1]);
  std::string received;
  char buffer[4096];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  bool timed_out = false;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd ready{pipe_ends[0], POLLIN, 0};
    const int polled = left.count() > 0 ? poll(&ready, 1, int(left.count())) : 0;
    if (polled < 0 && errno == EINTR) continue;
    if (polled <= 0) {
      timed_out = true;
      kill(child, SIGKILL);
      break;
    }
    const ssize_t n = read(pipe_ends[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    received.append(buffer, size_t(n));
  }
  close(pipe_ends[0]);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) fail(what + ": decoding its strings took longer than 5 s");
  if (WIFSIGNALED(status))
    fail(what + ": HDF5 crashed (signal " + std::to_string(WTERMSIG(status)) +
         ") on its damaged strings");
  std::vector<std::string> out;
  size_t at = 1;
  while (at + sizeof(std::uint64_t) <= received.size()) {
    std::uint64_t length = 0;
    std::memcpy(&length, received.data() + at, sizeof length);
    at += sizeof length;
    if (length > received.size() - at) break;
    out.push_back(received.substr(at, length));
    at += length;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || received.empty() || at != received.size())
    fail(what + ": its strings could not be decoded");
  if (received[0] == 1) throw InputError(out.at(0));
  return out;
}

void H5File::check_one_value(hid_t attr, bool text, const std::string& what) const {
  const Handle space = handle(H5Aget_space(attr), H5Sclose, what);
  if (check(H5Sget_simple_extent_npoints(space.id()), what) != 1)
    fail(what + ": it holds more or less than one value");
  const Handle type = handle(H5Aget_type(attr), H5Tclose, what);
  const H5T_class_t type_class = H5Tget_class(type.id());
  if (text ? type_class != H5T_STRING || H5Tis_variable_str(type.id()) <= 0
           : type_class != H5T_INTEGER && type_class != H5T_FLOAT)
    fail(what + (text ? ": not a variable-length string" : ": not a number"));
}

size_t H5File::stored_size(hid_t set, const std::string& what) const {
  const Handle type = handle(H5Dget_type(set), H5Tclose, what);
  return std::max<size_t>(check(H5Tget_size(type.id()), what), 1);
}

hsize_t H5File::fitting_values(const std::vector<hsize_t>& dims, size_t from, hsize_t rows,
                               size_t bytes, const std::string& what) const {
  hsize_t file_bytes = 0;
  if (H5Fget_filesize(file_.id(), &file_bytes) < 0) file_bytes = 0;
  std::error_code error;
  const std::uintmax_t on_disk = std::filesystem::file_size(path_, error);
  if (!error) file_bytes = std::max<hsize_t>(file_bytes, on_disk);
  // The product saturates at most + 1, so that it cannot overflow (a zero factor still makes 0).
  const hsize_t most = file_bytes / std::max<size_t>(bytes, 1);
  hsize_t values = rows;
  for (size_t k = from; k < dims.size(); ++k)
    values = dims[k] != 0 && values > most / dims[k] ? most + 1 : values * dims[k];
  if (values > most)
    fail(what + ": more values than a file of " + std::to_string(file_bytes) + " bytes holds");
  return values;
}

Handle H5File::handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) const {
  return Handle(check(id, what), close);
}

std::vector<hsize_t> H5File::dataset_dims(hid_t set, const std::string& what) const {
  const Handle space = handle(H5Dget_space(set), H5Sclose, what);
  std::vector<hsize_t> dims(check(H5Sget_simple_extent_ndims(space.id()), what));
  check(H5Sget_simple_extent_dims(space.id(), dims.data(), nullptr), what);
  return dims;
}

H5File::RowSelection H5File::select_rows(hid_t set, hsize_t first, hsize_t count,
                                         const std::string& what) const {
  Handle file = handle(H5Dget_space(set), H5Sclose, what);
  std::vector<hsize_t> size(check(H5Sget_simple_extent_ndims(file.id()), what));
  check(H5Sget_simple_extent_dims(file.id(), size.data(), nullptr), what);
  std::vector<hsize_t> start(size.size(), 0);
  start[0] = first;
  size[0] = count;
  check(H5Sselect_hyperslab(file.id(), H5S_SELECT_SET, start.data(), nullptr, size.data(), nullptr),
        what);
  Handle memory = handle(H5Screate_simple(int(size.size()), size.data(), nullptr), H5Sclose, what);
  const hssize_t values = check(H5Sget_simple_extent_npoints(memory.id()), what);
  return {std::move(file), std::move(memory), values};
}

Handle H5File::fixed_string_type(size_t capacity, const std::string& what) const {
  Handle type = handle(H5Tcopy(H5T_C_S1), H5Tclose, what);
  check(H5Tset_size(type.id(), capacity), what);
  check(H5Tset_strpad(type.id(), H5T_STR_NULLPAD), what);
  check(H5Tset_cset(type.id(), H5T_CSET_UTF8), what);
  return type;
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
