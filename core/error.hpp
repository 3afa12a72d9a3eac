#pragma once
/// Exceptions for bad input. Messages name the file, line, key or element at fault.

#include <stdexcept>
#include <string>
#include <utility>

namespace depthfem {

/// Raised for any malformed or inconsistent input (mesh files, scene files, parameters).
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An InputError about one parameter of an options struct (a mesh generator's `cells`, ...): the
/// code that read the parameter from a file adds where it came from.
class ParameterError : public InputError {
 public:
  ParameterError(std::string parameter, std::string reason)
      : InputError(parameter + ": " + reason),
        parameter_(std::move(parameter)),
        reason_(std::move(reason)) {}
  /// The parameter's name, as the options struct and the scene key spell it.
  const std::string& parameter() const { return parameter_; }
  /// What is wrong with it.
  const std::string& reason() const { return reason_; }

 private:
  std::string parameter_, reason_;
};

/// Raised when a computation cannot proceed (inverted element, failed solve), with the reason.
class SolveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// "FILE:LINE: WHAT" (LINE omitted when 0), the one format every reader uses.
std::string located(const std::string& file, long line, const std::string& what);

}  // namespace depthfem
