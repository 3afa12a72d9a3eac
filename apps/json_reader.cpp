#include "apps/json_reader.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "core/error.hpp"

namespace depthfem {

namespace {

using nlohmann::json;

// Rejects text that is too large or too deeply nested, before the parser sees it: counts the
// brackets outside strings.
void check_size_and_depth(const std::string& text, const std::string& where) {
  if (text.size() > kMaxJsonBytes) {
    throw InputError(where + ": " + std::to_string(text.size()) + " bytes, more than the " +
                     std::to_string(kMaxJsonBytes) + " a scene may have");
  }
  int depth = 0;
  long line = 1;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (c == '\n') ++line;
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) {
        throw InputError(located(
            where, line, "nested more than " + std::to_string(kMaxJsonDepth) + " levels deep"));
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

// Where the parser is, for messages: one entry per open object or array.
struct Frame {
  bool object;
  std::set<std::string> keys;  // objects: keys seen so far
  std::string key;             // objects: the key being read
  size_t index = 0;            // arrays: the element being read
};

std::string path_of(const std::vector<Frame>& frames) {
  std::string path;
  for (const Frame& f : frames) {
    if (f.object) {
      path += (path.empty() ? "" : ".") + f.key;
    } else {
      path += "[" + std::to_string(f.index) + "]";
    }
  }
  return path;
}

// An integer JSON value as 64 bits (none for other values and unsigned ones above 2^63).
std::optional<std::int64_t> as_int64(const json& v) {
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) return {};
    return static_cast<std::int64_t>(u);
  }
  if (v.is_number_integer()) return v.get<std::int64_t>();
  return {};
}

// The int held by `v`, read for `key` of `o`; `context` is the value shown when `v` is no integer.
int to_int(const JsonObject& o, const std::string& key, const json& v, const std::string& expected,
           const json& context) {
  const std::optional<std::int64_t> i = as_int64(v);
  if (!i) o.fail(key, "expected " + expected + ", found " + shown(context));
  if (*i < std::numeric_limits<int>::min() || *i > std::numeric_limits<int>::max())
    o.fail(key, "integer " + shown(v) + " is out of range (at most 2147483647 in magnitude)");
  return static_cast<int>(*i);
}

}  // namespace

json parse_json(const std::string& text, const std::string& where) {
  check_size_and_depth(text, where);
  std::vector<Frame> frames;
  // A child value finished: the next element of an enclosing array.
  const auto advance = [&] {
    if (!frames.empty() && !frames.back().object) ++frames.back().index;
  };
  const json::parser_callback_t track = [&](int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        frames.push_back({true, {}, {}, 0});
        break;
      case json::parse_event_t::array_start:
        frames.push_back({false, {}, {}, 0});
        break;
      case json::parse_event_t::key: {
        Frame& f = frames.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          throw InputError(where + ": " + path_of(frames) + ": duplicate key");
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames.pop_back();
        advance();
        break;
      case json::parse_event_t::value:
        advance();
        break;
    }
    return true;
  };
  try {
    return json::parse(text, track);
  } catch (const json::out_of_range&) {
    // The parser's only range error: a number beyond a double ("1e999"), which the library's
    // message would quote whole.
    const std::string path = path_of(frames);
    throw InputError(where + ": " + (path.empty() ? "" : path + ": ") +
                     "a number beyond the range of a double (about 1.8e308)");
  } catch (const json::parse_error& e) {
    // "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error ...":
    // keep what follows the library's tag.
    std::string what = e.what();
    const size_t tag_end = what.find("] ");
    if (tag_end != std::string::npos) what = what.substr(tag_end + 2);
    throw InputError(where + ": invalid JSON: " + what);
  }
}

std::string shown(const json& value) {
  std::string text = value.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

JsonObject::JsonObject(const nlohmann::json& j, std::string path, std::string file)
    : j_(j), path_(std::move(path)), file_(std::move(file)) {
  if (!j_.is_object())
    throw InputError(file_ + ": " + (path_.empty() ? "the scene" : path_) + ": expected an object");
}

std::string JsonObject::key_path(const std::string& key) const {
  if (key.empty()) return path_;
  return path_.empty() ? key : path_ + "." + key;
}

void JsonObject::fail(const std::string& key, const std::string& what) const {
  throw InputError(file_ + ": " + key_path(key) + ": " + what);
}

const nlohmann::json& JsonObject::at(const std::string& key) {
  used_.insert(key);
  if (!j_.contains(key)) fail(key, "missing required key");
  return j_.at(key);
}

double JsonObject::number(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_number()) fail(key, "expected a number, found " + shown(v));
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(key, "expected a finite number");
  return d;
}
double JsonObject::number(const std::string& key, double fallback) {
  return has(key) ? number(key) : (ignore(key), fallback);
}

int JsonObject::integer(const std::string& key) {
  const nlohmann::json& v = at(key);
  return to_int(*this, key, v, "an integer", v);
}
int JsonObject::integer(const std::string& key, int fallback) {
  return has(key) ? integer(key) : (ignore(key), fallback);
}

bool JsonObject::boolean(const std::string& key, bool fallback) {
  if (!has(key)) return fallback;
  const nlohmann::json& v = at(key);
  if (!v.is_boolean()) fail(key, "expected true or false, found " + shown(v));
  return v.get<bool>();
}

std::string JsonObject::string(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_string()) fail(key, "expected a string, found " + shown(v));
  return v.get<std::string>();
}
std::string JsonObject::string(const std::string& key, const std::string& fallback) {
  return has(key) ? string(key) : fallback;
}

Vec3 JsonObject::vec3(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array() || v.size() != 3)
    fail(key, "expected an array of 3 numbers, found " + shown(v));
  Vec3 out;
  for (int k = 0; k < 3; ++k) {
    if (!v[k].is_number() || !std::isfinite(v[k].get<double>()))
      fail(key, "expected an array of 3 numbers, found " + shown(v));
    out(k) = v[k].get<double>();
  }
  return out;
}
Vec3 JsonObject::vec3(const std::string& key, const Vec3& fallback) {
  return has(key) ? vec3(key) : fallback;
}

Eigen::Vector3i JsonObject::int3(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array() || v.size() != 3)
    fail(key, "expected an array of 3 integers, found " + shown(v));
  Eigen::Vector3i out;
  for (int k = 0; k < 3; ++k) {
    out(k) = to_int(*this, key, v[k], "an array of 3 integers", v);
  }
  return out;
}

std::vector<Index> JsonObject::indices(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array()) fail(key, "expected an array of node indices");
  std::vector<Index> out;
  for (const auto& e : v) {
    const std::optional<std::int64_t> i = as_int64(e);
    if (!i || *i < 0 || *i > std::numeric_limits<Index>::max())
      fail(key, "expected node indices in [0, 2147483647], found " + shown(e));
    out.push_back(static_cast<Index>(*i));
  }
  return out;
}

std::vector<double> JsonObject::numbers(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array() || v.empty()) fail(key, "expected a non-empty array of numbers");
  std::vector<double> out;
  for (const auto& e : v) {
    if (!e.is_number() || !std::isfinite(e.get<double>()))
      fail(key, "expected an array of finite numbers, found " + shown(e));
    out.push_back(e.get<double>());
  }
  return out;
}

std::vector<std::string> JsonObject::strings(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array() || v.empty()) fail(key, "expected a non-empty array of strings");
  std::vector<std::string> out;
  for (const auto& e : v) {
    if (!e.is_string()) fail(key, "expected an array of strings, found " + e.dump());
    out.push_back(e.get<std::string>());
  }
  return out;
}

JsonObject JsonObject::object(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_object()) fail(key, "expected an object, found " + shown(v));
  return JsonObject(v, key_path(key), file_);
}

std::vector<JsonObject> JsonObject::objects(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array()) fail(key, "expected an array of objects");
  std::vector<JsonObject> out;
  for (size_t k = 0; k < v.size(); ++k) {
    const std::string p = key_path(key) + "[" + std::to_string(k) + "]";
    if (!v[k].is_object())
      throw InputError(file_ + ": " + p + ": expected an object, found " + shown(v[k]));
    out.emplace_back(v[k], p, file_);
  }
  return out;
}

std::vector<std::string> JsonObject::keys() const {
  std::vector<std::string> out;
  for (auto it = j_.begin(); it != j_.end(); ++it) out.push_back(it.key());
  return out;
}

void JsonObject::finish() const {
  for (auto it = j_.begin(); it != j_.end(); ++it)
    if (!used_.count(it.key()))
      throw InputError(file_ + ": " + key_path(it.key()) + ": unknown key");
}

}  // namespace depthfem
