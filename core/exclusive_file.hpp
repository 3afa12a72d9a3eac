#pragma once
/// Files a run creates beside its results (the staging file, the sidecars' spares): each made
/// new under a name nobody else chose, exclusively (O_CREAT | O_EXCL: never an existing file,
/// never through a symbolic link), so that whoever can create files in the output folder cannot
/// redirect a write of the run to another file.

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>

namespace depthfem {

/// An open file descriptor, closed with its owner.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept;
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor();

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};

/// `prefix` followed by a dot and eight random hexadecimal digits.
std::string random_name(const std::string& prefix);

/// A file created new, and its path.
struct NewFile {
  FileDescriptor fd;
  std::string path;
};

/// Creates a new, empty file `directory`/`prefix`.XXXXXXXX (random digits) for reading and
/// writing, exclusively; tries other names while one exists. Throws InputError naming `what`
/// (the file the helper serves) when none can be created.
NewFile create_exclusive(const std::filesystem::path& directory, const std::string& prefix,
                         const std::string& what);

/// Writes all of `data` at `offset`, retrying short writes; false (errno set) on failure.
bool write_all_at(int fd, std::string_view data, off_t offset);

/// The whole content of the file open as `fd`; false (errno set) on failure.
bool read_all(int fd, std::string& out);

}  // namespace depthfem
