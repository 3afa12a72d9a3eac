#include "core/exclusive_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <random>

#include "core/error.hpp"

namespace depthfem {

FileDescriptor& FileDescriptor::operator=(FileDescriptor&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

FileDescriptor::~FileDescriptor() {
  if (fd_ >= 0) ::close(fd_);
}

std::string random_name(const std::string& prefix) {
  static thread_local std::mt19937 generator{std::random_device{}()};
  char digits[16];
  std::snprintf(digits, sizeof digits, ".%08x", unsigned(generator()));
  return prefix + digits;
}

NewFile create_exclusive(const std::filesystem::path& directory, const std::string& prefix,
                         const std::string& what) {
  constexpr int kTries = 32;
  for (int k = 0; k < kTries; ++k) {
    std::string path = (directory / random_name(prefix)).string();
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd >= 0) return {FileDescriptor(fd), std::move(path)};
    if (errno != EEXIST)
      throw InputError(located(what, 0, "cannot create " + path + ": " + std::strerror(errno)));
  }
  throw InputError(located(what, 0,
                           "cannot create a helper file " + (directory / prefix).string() +
                               ".*: " + std::to_string(kTries) + " random names all exist"));
}

bool write_all_at(int fd, std::string_view data, off_t offset) {
  while (!data.empty()) {
    const ssize_t n = ::pwrite(fd, data.data(), data.size(), offset);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      return false;
    }
    data.remove_prefix(size_t(n));
    offset += n;
  }
  return true;
}

bool read_all(int fd, std::string& out) {
  out.clear();
  char buffer[65536];
  for (off_t offset = 0;;) {
    const ssize_t n = ::pread(fd, buffer, sizeof buffer, offset);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    if (n == 0) return true;
    out.append(buffer, size_t(n));
    offset += n;
  }
}

}  // namespace depthfem
