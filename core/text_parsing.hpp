#pragma once
/// Helpers shared by the mesh and surface readers: line-by-line reading of text files with line
/// numbers, strict number parsing, and conversion of the flat arrays they fill to Eigen matrices.

#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// Whole-token parse of a decimal integer with optional sign ("12", "-3", "+4"); rejects "1.0",
/// "7x".
std::optional<long long> parse_integer(std::string_view token);

/// Whole-token parse of a finite double ("1e3", "-.5", "+2"); rejects "nan", "inf", "1e999",
/// "1.0abc".
std::optional<double> parse_finite_double(std::string_view token);

/// Copies `flat`, row-major with Matrix::ColsAtCompileTime values per row, into a `Matrix`
/// (Points, TetIndices, TriIndices).
template <class Matrix>
Matrix from_row_major(const std::vector<typename Matrix::Scalar>& flat) {
  constexpr int kCols = Matrix::ColsAtCompileTime;
  using RowMajor = Eigen::Matrix<typename Matrix::Scalar, Eigen::Dynamic, kCols, Eigen::RowMajor>;
  return Eigen::Map<const RowMajor>(flat.data(), static_cast<Eigen::Index>(flat.size() / kCols),
                                    kCols);
}

/// Reads a text file one significant line at a time, split into whitespace-separated tokens.
/// Blank lines are skipped, and so is everything after `comment` on a line when `comment` is not
/// '\0'. Errors raised through it carry "FILE:LINE:". Number conversions take `what`, a callable
/// returning the description used in the message ("x coordinate of node 12"), which is only built
/// when the conversion fails, so that reading large files allocates no message strings.
class LineReader {
 public:
  /// Opens `path`; throws InputError "FILE: cannot open" when it cannot be read.
  explicit LineReader(const std::string& path, char comment = '\0');

  /// Advances to the next significant line; false at end of file.
  bool next();
  /// Tokens of the current line, valid until the next call to `next`.
  const std::vector<std::string_view>& tokens() const { return tokens_; }
  /// Number of the current line (1-based); at end of file, the number of lines in the file.
  long line() const { return line_; }

  /// Throws InputError "FILE:LINE: WHAT" for the current line.
  [[noreturn]] void fail(const std::string& what) const;
  /// Throws unless the current line has exactly `n` tokens ("expected N values for WHAT, found M").
  template <class What>
  void expect_tokens(size_t n, const What& what) const {
    if (tokens_.size() != n) fail_token_count(n, what());
  }

  /// Strict integer (see parse_integer).
  template <class What>
  long long to_integer(std::string_view token, const What& what) const {
    if (const auto v = parse_integer(token)) return *v;
    fail_number("an integer", token, what());
  }
  /// Strict integer in [0, max Index]: a count or a 0-based position.
  template <class What>
  Index to_count(std::string_view token, const What& what) const {
    const auto v = parse_integer(token);
    if (v && *v >= 0 && *v <= std::numeric_limits<Index>::max()) return static_cast<Index>(*v);
    fail_number("a non-negative integer below 2^31", token, what());
  }
  /// Strict finite double (see parse_finite_double).
  template <class What>
  double to_double(std::string_view token, const What& what) const {
    if (const auto v = parse_finite_double(token)) return *v;
    fail_number("a finite number", token, what());
  }

 private:
  [[noreturn]] void fail_number(const char* expected, std::string_view token,
                                const std::string& what) const;
  [[noreturn]] void fail_token_count(size_t n, const std::string& what) const;

  std::string file_;
  char comment_;
  std::ifstream stream_;
  std::string buffer_;
  std::vector<std::string_view> tokens_;
  long line_ = 0;
};

}  // namespace depthfem
