#include "apps/json_reader.hpp"

#include <cmath>

#include "core/error.hpp"

namespace depthfem {

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
  if (!v.is_number()) fail(key, "expected a number, found " + v.dump());
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(key, "expected a finite number");
  return d;
}
double JsonObject::number(const std::string& key, double fallback) {
  return has(key) ? number(key) : (ignore(key), fallback);
}

int JsonObject::integer(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_number_integer()) fail(key, "expected an integer, found " + v.dump());
  return v.get<int>();
}
int JsonObject::integer(const std::string& key, int fallback) {
  return has(key) ? integer(key) : (ignore(key), fallback);
}

bool JsonObject::boolean(const std::string& key, bool fallback) {
  if (!has(key)) return fallback;
  const nlohmann::json& v = at(key);
  if (!v.is_boolean()) fail(key, "expected true or false, found " + v.dump());
  return v.get<bool>();
}

std::string JsonObject::string(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_string()) fail(key, "expected a string, found " + v.dump());
  return v.get<std::string>();
}
std::string JsonObject::string(const std::string& key, const std::string& fallback) {
  return has(key) ? string(key) : fallback;
}

Vec3 JsonObject::vec3(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array() || v.size() != 3)
    fail(key, "expected an array of 3 numbers, found " + v.dump());
  Vec3 out;
  for (int k = 0; k < 3; ++k) {
    if (!v[k].is_number() || !std::isfinite(v[k].get<double>()))
      fail(key, "expected an array of 3 numbers, found " + v.dump());
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
    fail(key, "expected an array of 3 integers, found " + v.dump());
  Eigen::Vector3i out;
  for (int k = 0; k < 3; ++k) {
    if (!v[k].is_number_integer()) fail(key, "expected an array of 3 integers, found " + v.dump());
    out(k) = v[k].get<int>();
  }
  return out;
}

std::vector<Index> JsonObject::indices(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array()) fail(key, "expected an array of node indices");
  std::vector<Index> out;
  for (const auto& e : v) {
    if (!e.is_number_integer()) fail(key, "expected an array of node indices, found " + e.dump());
    out.push_back(e.get<Index>());
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
  if (!v.is_object()) fail(key, "expected an object, found " + v.dump());
  return JsonObject(v, key_path(key), file_);
}

std::vector<JsonObject> JsonObject::objects(const std::string& key) {
  const nlohmann::json& v = at(key);
  if (!v.is_array()) fail(key, "expected an array of objects");
  std::vector<JsonObject> out;
  for (size_t k = 0; k < v.size(); ++k) {
    const std::string p = key_path(key) + "[" + std::to_string(k) + "]";
    if (!v[k].is_object())
      throw InputError(file_ + ": " + p + ": expected an object, found " + v[k].dump());
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
