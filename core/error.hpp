#pragma once
/// Exceptions for bad input. Messages name the file, line, key or element at fault.

#include <stdexcept>
#include <string>

namespace depthfem {

/// Raised for any malformed or inconsistent input (mesh files, scene files, parameters).
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Raised when a computation cannot proceed (inverted element, failed solve), with the reason.
class SolveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// "FILE:LINE: WHAT" (LINE omitted when 0), the one format every reader uses.
std::string located(const std::string& file, long line, const std::string& what);

}  // namespace depthfem
