#pragma once
/// A thin, checked C++ layer over the HDF5 C library for the files depthfem writes and reads:
/// owned identifiers, typed datasets and attributes named by absolute path, and every failure
/// turned into an InputError that names the file and the object.

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

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

/// An open HDF5 file with checked reads and writes. Objects are named by absolute path
/// ("/steps/000001/x"); every failure throws InputError "FILE: cannot ... OBJECT".
class H5File {
 public:
  /// Creates (truncates) `path` for writing. Keeps HDF5's default (oldest) file format on purpose:
  /// the 1.10 format marks a file open for writing in its superblock, and the file of a killed
  /// run then cannot be opened without `h5clear -s`.
  static H5File create(const std::string& path);
  /// Opens `path` read-only.
  static H5File open(const std::string& path);

  /// Throws InputError "FILE: WHAT".
  [[noreturn]] void fail(const std::string& what) const;

  /// Writes file buffers and metadata to disk, so that the file is complete as it stands.
  void flush() const;
  /// Creates a group that lists its attributes in the order they are written.
  void create_group(const std::string& name) const;
  /// Removes the link `name` (the space of the object is not reclaimed).
  void remove(const std::string& name) const;

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
  void write_strings(const std::string& name, const std::vector<std::string>& values) const;

  /// Sets a scalar numeric attribute of `object`, replacing any previous value.
  template <class T>
  void set_attribute(const std::string& object, const std::string& name, T value) const {
    write_attribute(object, name, H5Type<T>::file(), H5Type<T>::memory(), &value);
  }
  /// Sets a scalar string attribute of `object`, replacing any previous value.
  void set_string_attribute(const std::string& object, const std::string& name,
                            const std::string& value) const;

  /// Whether the link `name` exists (false also when its parent group does not).
  bool exists(const std::string& name) const;
  /// Dimensions of dataset `name`.
  std::vector<hsize_t> dims(const std::string& name) const;
  /// All values of dataset `name` as doubles, row-major.
  std::vector<double> read_doubles(const std::string& name) const;
  /// All values of a 1D dataset of variable-length strings.
  std::vector<std::string> read_strings(const std::string& name) const;

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
  std::string string_attribute(const std::string& object, const std::string& name) const;

  /// Names of the links in `group`, in increasing name order.
  std::vector<std::string> link_names(const std::string& group) const;
  /// Names of the attributes of `object`, in the order they were written.
  std::vector<std::string> attribute_names(const std::string& object) const;

 private:
  H5File(std::string path, hid_t id, const char* failure);

  /// Returns `status`, or throws "FILE: WHAT" when it is negative (HDF5's failure value).
  template <class Status>
  Status check(Status status, const std::string& what) const {
    if (status < 0) fail(what);
    return status;
  }
  Handle handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) const;
  /// Variable-length UTF-8 string type (what h5py reads as str).
  Handle string_type(const std::string& what) const;
  void write_raw(const std::string& name, hid_t file_type, hid_t memory_type,
                 const std::vector<hsize_t>& dims, const void* data) const;
  void write_attribute(const std::string& object, const std::string& name, hid_t file_type,
                       hid_t memory_type, const void* value) const;
  Handle open_attribute(const std::string& object, const std::string& name,
                        const std::string& what) const;

  std::string path_;
  Handle file_;
};

}  // namespace depthfem
