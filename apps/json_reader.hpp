#pragma once
/// Strict reading of JSON objects: every key must be known, every value of the right type, and
/// every error names the full key path ("bodies[0].material.C1: expected a number").

#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace depthfem {

/// Limits on JSON text, checked before parsing: scene files are small and shallow, and a parser
/// fed megabytes of nesting would exhaust the stack or the memory.
inline constexpr size_t kMaxJsonBytes = 16 << 20;
inline constexpr int kMaxJsonDepth = 64;

/// Parses JSON `text` strictly: at most kMaxJsonBytes and kMaxJsonDepth levels of nesting, no
/// duplicate keys. Throws InputError "WHERE:LINE: ..." (size, depth, syntax) or "WHERE: KEY.PATH:
/// duplicate key".
nlohmann::json parse_json(const std::string& text, const std::string& where);

/// One line showing a JSON value in a message: at most 60 characters, invalid UTF-8 replaced.
std::string shown(const nlohmann::json& value);

/// A JSON object being read. Keys read through it are marked; finish() rejects the rest.
class JsonObject {
 public:
  /// `path` names the object in messages ("" for the root); `file` prefixes every message.
  JsonObject(const nlohmann::json& j, std::string path, std::string file);

  bool has(const std::string& key) const { return j_.contains(key); }
  /// Every key of the object, in the JSON library's order.
  std::vector<std::string> keys() const;
  double number(const std::string& key);
  double number(const std::string& key, double fallback);
  /// An integer that fits an int; larger ones are refused, never truncated.
  int integer(const std::string& key);
  int integer(const std::string& key, int fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string string(const std::string& key);
  std::string string(const std::string& key, const std::string& fallback);
  Vec3 vec3(const std::string& key);
  Vec3 vec3(const std::string& key, const Vec3& fallback);
  Eigen::Vector3i int3(const std::string& key);
  /// An array of node indices, each in [0, 2^31).
  std::vector<Index> indices(const std::string& key);
  /// A non-empty array of finite numbers.
  std::vector<double> numbers(const std::string& key);
  /// A non-empty array of strings.
  std::vector<std::string> strings(const std::string& key);
  JsonObject object(const std::string& key);
  std::vector<JsonObject> objects(const std::string& key);
  /// A string key naming one of `names` (the first is the default when the key is absent);
  /// anything else fails with "unknown WHAT 'x' (expected a, b or c)".
  template <class E>
  E choice(const std::string& key, const std::string& what,
           std::initializer_list<std::pair<const char*, E>> names) {
    const std::string value = string(key, names.begin()->first);
    std::string expected;
    size_t k = 0;
    for (const auto& [name, e] : names) {
      if (value == name) return e;
      expected += (k == 0 ? "" : k + 1 == names.size() ? " or " : ", ") + std::string(name);
      ++k;
    }
    fail(key, "unknown " + what + " '" + value + "' (expected " + expected + ")");
  }
  /// Marks a key as known without reading it (free-text fields such as "description").
  void ignore(const std::string& key) { used_.insert(key); }

  /// Throws InputError for the first key that was never read.
  void finish() const;
  /// An InputError "FILE: PATH.KEY: what".
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  const std::string& path() const { return path_; }

 private:
  const nlohmann::json& at(const std::string& key);
  std::string key_path(const std::string& key) const;

  const nlohmann::json& j_;
  std::string path_, file_;
  std::set<std::string> used_;
};

}  // namespace depthfem
