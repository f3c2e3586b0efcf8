#include "pointdag/container/json_fields.h"

#include <cmath>

namespace pointdag {

StatusOr<const nlohmann::json*> JsonFields::Lookup(std::string_view path) const {
  const nlohmann::json* node = &root_;
  const std::string_view full = path;
  while (!path.empty()) {
    if (path.front() == '/') path.remove_prefix(1);
    const size_t end = path.find('/');
    const std::string_view key = path.substr(0, end);
    if (!node->is_object()) return Refuse(full.substr(0, static_cast<size_t>(key.data() - full.data())), "is not an object");
    path.remove_prefix(end == std::string_view::npos ? path.size() : end);
    const auto it = node->find(key);
    if (it == node->end()) return nullptr;
    node = &*it;
  }
  return node;
}

const nlohmann::json* JsonFields::Find(std::string_view path) const {
  const auto found = Lookup(path);
  return found.ok() ? *found : nullptr;
}

Status JsonFields::Refuse(std::string_view path, const std::string& why) const {
  return {code_, context_ + " '" + std::string(path.substr(path.starts_with('/') ? 1 : 0)) + "' " + why};
}

StatusOr<const nlohmann::json*> JsonFields::Required(std::string_view path) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Lookup(path));
  if (!member) return Refuse(path, "is missing");
  return member;
}

StatusOr<int64_t> JsonFields::Int(std::string_view path, int64_t min, int64_t max) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Required(path));
  const std::string range = "outside " + std::to_string(min) + ".." + std::to_string(max);
  if (member->is_number_unsigned()) {
    const uint64_t v = member->get<uint64_t>();
    if (max < 0 || v > static_cast<uint64_t>(max) || static_cast<int64_t>(v) < min) return Refuse(path, "is " + range);
    return static_cast<int64_t>(v);
  }
  if (!member->is_number_integer()) return Refuse(path, "is not an integer");
  const int64_t v = member->get<int64_t>();
  if (v < min || v > max) return Refuse(path, "is " + range);
  return v;
}

StatusOr<uint64_t> JsonFields::Uint(std::string_view path, uint64_t max) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Required(path));
  if (!member->is_number_integer()) return Refuse(path, "is not an integer");
  if (!member->is_number_unsigned()) return Refuse(path, "is negative");
  const uint64_t v = member->get<uint64_t>();
  if (v > max) return Refuse(path, "is above " + std::to_string(max));
  return v;
}

StatusOr<double> JsonFields::Number(std::string_view path) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Required(path));
  if (!member->is_number()) return Refuse(path, "is not a number");
  const double v = member->get<double>();
  if (!std::isfinite(v)) return Refuse(path, "is not finite");
  return v;
}

StatusOr<std::string> JsonFields::String(std::string_view path) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Required(path));
  if (!member->is_string()) return Refuse(path, "is not a string");
  return member->get<std::string>();
}

StatusOr<std::array<double, 3>> JsonFields::Vec3(std::string_view path) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Required(path));
  if (!member->is_array() || member->size() != 3) return Refuse(path, "is not three numbers");
  std::array<double, 3> out{};
  for (size_t i = 0; i < 3; ++i) {
    const nlohmann::json& v = (*member)[i];
    if (!v.is_number() || !std::isfinite(v.get<double>())) return Refuse(path, "is not three finite numbers");
    out[i] = v.get<double>();
  }
  return out;
}

StatusOr<const nlohmann::json*> JsonFields::Array(std::string_view path) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Required(path));
  if (!member->is_array()) return Refuse(path, "is not an array");
  return member;
}

StatusOr<uint64_t> JsonFields::UintOr(std::string_view path, uint64_t max, uint64_t fallback) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Lookup(path));
  return member ? Uint(path, max) : fallback;
}

StatusOr<std::string> JsonFields::StringOr(std::string_view path, std::string fallback) const {
  ASSIGN_OR_RETURN(const nlohmann::json* member, Lookup(path));
  return member ? String(path) : StatusOr<std::string>(std::move(fallback));
}

}  // namespace pointdag
