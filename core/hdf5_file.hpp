#pragma once
/// A thin, checked C++ layer over the HDF5 C library for the files depthfem writes and reads:
/// owned identifiers, typed datasets and attributes named by absolute path, and every failure
/// turned into an InputError that names the file and the object.

#include <hdf5.h>

#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
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
  /// Creates `path` new for writing (never an existing file, nor through a symbolic link), in
  /// the HDF5 1.10 file format that single-writer / multiple-reader (SWMR) access needs.
  /// Messages name it `name` (the results file a staging file becomes) until it is renamed.
  static H5File create(const std::string& path, const std::string& name);
  /// Opens `path` read-only as a SWMR reader: the file may be one that a writer is still
  /// writing, one whose writer was killed, or a closed one. A metadata read whose checksum fails
  /// is tried kMetadataReadAttempts times in all, so that a damaged file fails within about a
  /// millisecond per damaged object.
  static H5File open(const std::string& path);
  /// Tries of a SWMR reader's metadata read before it fails (see open).
  static constexpr unsigned kMetadataReadAttempts = 20;

  /// Renames the open file to `path` (same file system), which messages then name.
  void rename(const std::string& path);

  /// Switches the writer to SWMR mode: from now on readers may open the file while it is
  /// written, and every flush leaves it consistent for them, but no object (group, dataset,
  /// attribute) can be created any more; datasets can grow and be written.
  void start_swmr_write() const;

  /// Throws InputError "FILE: WHAT".
  [[noreturn]] void fail(const std::string& what) const;

  /// Writes file buffers and metadata to disk, so that the file is complete as it stands.
  void flush() const;

  /// Disk space allocated past the end of what a file uses, given back when it goes out of scope.
  class Reservation {
   public:
    explicit Reservation(const H5File& file) : file_(file) {}
    Reservation(const Reservation&) = delete;
    Reservation& operator=(const Reservation&) = delete;
    ~Reservation() { file_.give_back(); }

   private:
    const H5File& file_;
  };
  /// Allocates `bytes` of disk space past the end of what the file uses, for as long as the
  /// returned reservation lives, or throws saying the disk is full. Writes that stay within them
  /// cannot fail for want of space: HDF5 cannot recover from a write that fails half done (the
  /// file's end recorded past its real end).
  [[nodiscard]] Reservation reserve(hsize_t bytes) const;
  /// Creates a group that lists its attributes in the order they are written.
  void create_group(const std::string& name) const;

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
  /// Creates dataset `name` of rows of `row_dims` values of `type` each (no dims: one value per
  /// row), with no rows yet; write_rows grows it. Chunked by rows, about 4 KiB or one row a
  /// chunk.
  void create_rows(const std::string& name, hid_t type, const std::vector<hsize_t>& row_dims) const;
  /// Writes `count` rows from `first` of a dataset made by create_rows, growing it to
  /// first + count rows when it has fewer; `data` holds them row-major in `memory_type`.
  void write_rows(const std::string& name, hsize_t first, hsize_t count, hid_t memory_type,
                  const void* data) const;
  /// Writes the values of `a` (row-major) as row `row` of a dataset made by create_rows.
  template <class Derived>
  void write_row(const std::string& name, hsize_t row, const Eigen::MatrixBase<Derived>& a) const {
    using T = typename Derived::Scalar;
    const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> row_major = a;
    write_rows(name, row, 1, H5Type<T>::memory(), row_major.data());
  }
  /// Writes `value` as row `row` of a dataset of scalars made by create_rows.
  template <class T>
  requires std::is_arithmetic_v<T>
  void write_row(const std::string& name, hsize_t row, T value) const {
    write_rows(name, row, 1, H5Type<T>::memory(), &value);
  }
  /// Sets the number of rows of a dataset made by create_rows.
  void set_rows(const std::string& name, hsize_t rows) const;
  /// Values of rows [first, first + count) of dataset `name` as doubles, row-major; throws
  /// when the dataset has fewer rows, or when they would take more bytes than the file has (so
  /// that a damaged size cannot make a reader allocate more than 8 times the file).
  std::vector<double> read_rows(const std::string& name, hsize_t first, hsize_t count) const;

  /// Creates a scalar dataset holding a string of at most `capacity` bytes, written in place by
  /// write_text (h5py reads it as bytes).
  void create_text(const std::string& name, size_t capacity) const;
  /// Writes `value` into a dataset made by create_text, cut to its capacity.
  void write_text(const std::string& name, const std::string& value) const;
  /// Creates a dataset of rows of strings of at most `capacity` bytes each, with no rows yet.
  void create_text_rows(const std::string& name, size_t capacity) const;
  /// Replaces the rows of a dataset made by create_text_rows by `values`, each cut to its capacity.
  void write_text_rows(const std::string& name, const std::vector<std::string>& values) const;
  /// The strings of a dataset made by create_text (one) or create_text_rows; throws when they
  /// would take more bytes than the file has.
  std::vector<std::string> read_texts(const std::string& name) const;

  /// Creates a dataset of `dims` doubles that reads as zeros and takes no space in the file: it
  /// is never written, so HDF5 allocates no storage and returns its fill value 0.
  void create_zeros(const std::string& name, const std::vector<hsize_t>& dims) const;
  /// Creates `name` as a view of rows [first_row, first_row + num_rows) of dataset `source` of
  /// this file (an HDF5 virtual dataset: it holds no data, readers see the source's values).
  void create_row_view(const std::string& name, const std::string& source, hsize_t first_row,
                       hsize_t num_rows) const;
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
  /// The class of the values of dataset `name`: H5T_INTEGER, H5T_FLOAT, H5T_STRING, ...
  H5T_class_t type_class(const std::string& name) const;
  /// All values of dataset `name` as doubles, row-major (at most what the file can hold).
  std::vector<double> read_doubles(const std::string& name) const;
  /// All values of a 1D dataset of variable-length strings (at most what the file can hold).
  std::vector<std::string> read_strings(const std::string& name) const;

  /// Scalar numeric attribute of `object`; throws unless it holds one number.
  template <class T>
  T attribute(const std::string& object, const std::string& name) const {
    const std::string what = "cannot read attribute " + name + " of " + object;
    const Handle attr = open_attribute(object, name, what);
    check_one_value(attr.id(), false, what);
    T value{};
    check(H5Aread(attr.id(), H5Type<T>::memory(), &value), what);
    return value;
  }
  /// Scalar string attribute of `object`; throws unless it holds one variable-length string.
  std::string string_attribute(const std::string& object, const std::string& name) const;
  /// Scalar string attributes `names` of `object`, read together (see decode_strings).
  std::vector<std::string> string_attributes(const std::string& object,
                                             const std::vector<std::string>& names) const;

 private:
  H5File(std::string path, std::string name, hid_t id, const char* failure);

  /// Returns `status`, or throws "FILE: WHAT" when it is negative (HDF5's failure value).
  template <class Status>
  Status check(Status status, const std::string& what) const {
    if (status < 0) fail(what);
    return status;
  }
  Handle handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) const;
  /// Variable-length UTF-8 string type (what h5py reads as str).
  Handle string_type(const std::string& what) const;
  /// UTF-8 strings of `capacity` bytes, padded with NUL.
  Handle fixed_string_type(size_t capacity, const std::string& what) const;
  /// Rows [first, first + count) of the open dataset `set`: its file space with them selected,
  /// a memory space of their shape, and how many values they hold.
  struct RowSelection {
    Handle file, memory;
    hssize_t values;
  };
  RowSelection select_rows(hid_t set, hsize_t first, hsize_t count, const std::string& what) const;
  /// Cuts the file back to the end of the space it uses (errors leave it longer, which is
  /// harmless).
  void give_back() const noexcept;
  /// The end of the space the file uses (HDF5's end of allocation) and its file descriptor.
  std::pair<off_t, int> end_and_descriptor(const std::string& what) const;
  /// Dimensions of the open dataset `set`.
  std::vector<hsize_t> dataset_dims(hid_t set, const std::string& what) const;
  void write_raw(const std::string& name, hid_t file_type, hid_t memory_type,
                 const std::vector<hsize_t>& dims, const void* data) const;
  void write_attribute(const std::string& object, const std::string& name, hid_t file_type,
                       hid_t memory_type, const void* value) const;
  Handle open_attribute(const std::string& object, const std::string& name,
                        const std::string& what) const;
  /// Throws "FILE: WHAT: ..." unless attribute `attr` holds one value: a number, or with `text`
  /// a variable-length string (H5Aread writes every value it holds into one value's memory).
  void check_one_value(hid_t attr, bool text, const std::string& what) const;
  /// Throws "FILE: WHAT: ..." unless the values of `rows` rows of `dims` (the product of `dims`
  /// from dimension `from` on, times `rows`), of `bytes` bytes each in the file, fit into the
  /// file's size: a reader allocates no more than the file could hold. Returns their number.
  hsize_t fitting_values(const std::vector<hsize_t>& dims, size_t from, hsize_t rows, size_t bytes,
                         const std::string& what) const;
  /// Bytes of one value of the open dataset `set` in the file (at least 1).
  size_t stored_size(hid_t set, const std::string& what) const;
  /// Throws "FILE: WHAT: ..." unless each of the `count` variable-length strings of the open
  /// dataset `set` (stored contiguously, as depthfem stores them) names an object of an intact
  /// global heap collection of the file, as long as the string: HDF5 1.10 checks neither before
  /// it copies the object (H5HG_read), and a damaged reference or collection made it read and
  /// write out of bounds or loop for ever.
  void check_string_references(hid_t set, hsize_t count, const std::string& what) const;
  /// Runs `decode` in a child process (within 5 s) and returns the strings it returns, or
  /// rethrows its InputError: for the strings of attributes, whose heap references HDF5's API
  /// does not show (check_string_references), so that a damaged heap that crashes HDF5 ends in
  /// "FILE: WHAT: HDF5 crashed ..." (or hangs it, in "... took longer than 5 s").
  std::vector<std::string> decode_strings(const std::function<std::vector<std::string>()>& decode,
                                          const std::string& what) const;

  std::string path_;
  std::string name_;  ///< the file as messages name it
  Handle file_;
};

}  // namespace depthfem
