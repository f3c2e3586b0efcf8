// Who may do what (proto/PROTOCOL.md §6): bearer tokens with a write and a read scope, and CORS.
//
// Contract: a presented token is compared in time independent of its content and of both tokens'
// lengths (fixed-size digests, the configured ones computed once). `Bearer` is matched without
// regard to case. A header holding several credentials (the transport joins repeated
// Authorization fields with ", ") is malformed: never "the last one wins".
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace pointdag::server {

enum class Scope { kNone, kRead, kWrite };

class AccessPolicy {
 public:
  // `write_token` empty: writes are open. `read_token` empty: no read-only token.
  AccessPolicy(const std::string& write_token, const std::string& read_token, bool require_token_for_reads);

  enum class Verdict { kAllowed, kMalformed, kUnauthenticated, kForbidden };
  // May a request with this Authorization header value do something that needs `needed`?
  // kMalformed: 400; kUnauthenticated: 401 (no or an unknown token); kForbidden: 403 (a read token for a write).
  Verdict Check(const std::string& authorization, Scope needed) const;
  bool reads_need_token() const { return reads_need_token_; }

 private:
  using Digest = std::array<uint8_t, 16>;
  static Digest DigestOf(const std::string& token);
  static bool SameDigest(const Digest& a, const Digest& b);
  std::optional<Digest> write_, read_;
  bool reads_need_token_;
};

// CORS: `allowed` holds "*" or exact origins.
class CorsPolicy {
 public:
  explicit CorsPolicy(std::vector<std::string> allowed);
  // The headers for an answer to a request from `origin` (empty when the request had none).
  std::vector<std::pair<std::string, std::string>> Headers(const std::string& origin) const;

 private:
  std::vector<std::string> allowed_;
  bool any_;
};

}  // namespace pointdag::server
