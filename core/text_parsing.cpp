#include "core/text_parsing.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>

#include "core/error.hpp"

namespace depthfem {

namespace {
// std::from_chars takes no leading '+'; accept one in front of a digit or '.'.
std::string_view without_plus(std::string_view token) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
    token.remove_prefix(1);
  }
  return token;
}

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
}  // namespace

std::optional<long long> parse_integer(std::string_view token) {
  token = without_plus(token);
  long long v = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size()) return {};
  return v;
}

std::optional<double> parse_finite_double(std::string_view token) {
  token = without_plus(token);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size() ||
      !std::isfinite(v)) {
    return {};
  }
  return v;
}

LineReader::LineReader(const std::string& path, char comment)
    : file_(path), comment_(comment), stream_(path) {
  std::error_code ec;  // a directory opens as a stream but cannot be read
  if (!stream_ || std::filesystem::is_directory(path, ec)) {
    throw InputError(located(file_, 0, "cannot open file"));
  }
}

bool LineReader::next() {
  tokens_.clear();
  while (std::getline(stream_, buffer_)) {
    ++line_;
    std::string_view rest(buffer_);
    if (comment_ != '\0') rest = rest.substr(0, rest.find(comment_));
    while (!rest.empty()) {
      size_t begin = 0;
      while (begin < rest.size() && is_space(rest[begin])) ++begin;
      size_t end = begin;
      while (end < rest.size() && !is_space(rest[end])) ++end;
      if (end > begin) tokens_.push_back(rest.substr(begin, end - begin));
      rest.remove_prefix(end);
    }
    if (!tokens_.empty()) return true;
  }
  if (stream_.bad()) fail("read error");
  return false;
}

void LineReader::fail(const std::string& what) const {
  throw InputError(located(file_, line_, what));
}

void LineReader::fail_number(const char* expected, std::string_view token,
                             const std::string& what) const {
  fail("expected " + std::string(expected) + " for " + what + ", found '" + std::string(token) +
       "'");
}

void LineReader::fail_token_count(size_t n, const std::string& what) const {
  fail("expected " + std::to_string(n) + " values for " + what + ", found " +
       std::to_string(tokens_.size()));
}

}  // namespace depthfem
