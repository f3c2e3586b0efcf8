// Typed, checked reads of JSON that came from outside: .pdag metadata, a server's dataset
// description or hierarchy page. nlohmann's own accessors throw on a wrong type (`get<>`,
// `value()`) or are undefined on a missing key (`operator[]` on a const object); these return a
// Status naming the member instead, so hostile JSON can only ever be refused.
//
// Members are named by a path of object keys, "/source/points"; every step must be an object.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "pointdag/status.h"

namespace pointdag {

class JsonFields {
 public:
  // `context` starts every message (".pdag metadata"); `code` is the status of every refusal.
  JsonFields(const nlohmann::json& root, std::string context, StatusCode code = StatusCode::kCorrupt)
      : root_(root), context_(std::move(context)), code_(code) {}

  // The member, or null when it (or an object on its path) is absent or the path crosses a non-object.
  const nlohmann::json* Find(std::string_view path) const;
  bool Has(std::string_view path) const { return Find(path) != nullptr; }

  StatusOr<int64_t> Int(std::string_view path, int64_t min, int64_t max) const;
  StatusOr<uint64_t> Uint(std::string_view path, uint64_t max) const;
  StatusOr<double> Number(std::string_view path) const;  // finite
  StatusOr<std::string> String(std::string_view path) const;
  StatusOr<std::array<double, 3>> Vec3(std::string_view path) const;  // three finite numbers
  StatusOr<const nlohmann::json*> Array(std::string_view path) const;

  // Absent: the fallback. Present with the wrong type or out of range, or a path through a
  // non-object: still an error.
  StatusOr<uint64_t> UintOr(std::string_view path, uint64_t max, uint64_t fallback) const;
  StatusOr<std::string> StringOr(std::string_view path, std::string fallback) const;

 private:
  StatusOr<const nlohmann::json*> Lookup(std::string_view path) const;  // null when absent
  StatusOr<const nlohmann::json*> Required(std::string_view path) const;
  Status Refuse(std::string_view path, const std::string& why) const;

  const nlohmann::json& root_;
  std::string context_;
  StatusCode code_;
};

}  // namespace pointdag
