#include "access.h"

#include <xxhash.h>

#include <algorithm>
#include <cctype>
#include <cstring>

namespace pointdag::server {
namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t'; }

std::string Trim(const std::string& text) {
  size_t a = 0, b = text.size();
  while (a < b && IsSpace(text[a])) ++a;
  while (b > a && IsSpace(text[b - 1])) --b;
  return text.substr(a, b - a);
}

bool EqualsIgnoringCase(const std::string& a, const char* b) {
  if (a.size() != std::strlen(b)) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) != b[i]) return false;
  }
  return true;
}

}  // namespace

AccessPolicy::AccessPolicy(const std::string& write_token, const std::string& read_token, bool require_token_for_reads)
    : reads_need_token_(require_token_for_reads && !(write_token.empty() && read_token.empty())) {
  if (!write_token.empty()) write_ = DigestOf(write_token);
  if (!read_token.empty()) read_ = DigestOf(read_token);
}

AccessPolicy::Digest AccessPolicy::DigestOf(const std::string& token) {
  const XXH128_hash_t h = XXH3_128bits(token.data(), token.size());
  Digest d;
  for (int i = 0; i < 8; ++i) {
    d[static_cast<size_t>(i)] = static_cast<uint8_t>(h.low64 >> (8 * i));
    d[static_cast<size_t>(8 + i)] = static_cast<uint8_t>(h.high64 >> (8 * i));
  }
  return d;
}

bool AccessPolicy::SameDigest(const Digest& a, const Digest& b) {
  uint8_t diff = 0;  // every byte compared, whichever differs first
  for (size_t i = 0; i < a.size(); ++i) diff = static_cast<uint8_t>(diff | (a[i] ^ b[i]));
  return diff == 0;
}

AccessPolicy::Verdict AccessPolicy::Check(const std::string& authorization, Scope needed) const {
  if (authorization.find(',') != std::string::npos) return Verdict::kMalformed;  // several credentials
  const bool open = needed == Scope::kNone || (needed == Scope::kWrite && !write_) ||
                    (needed == Scope::kRead && !reads_need_token_);
  if (open) return Verdict::kAllowed;
  const std::string value = Trim(authorization);
  const size_t space = value.find_first_of(" \t");
  if (space == std::string::npos || !EqualsIgnoringCase(value.substr(0, space), "bearer")) return Verdict::kUnauthenticated;
  const Digest given = DigestOf(Trim(value.substr(space)));
  // Both compared always, so the time says nothing about which token (if any) matched.
  const bool is_write = write_ && SameDigest(given, *write_);
  const bool is_read = read_ && SameDigest(given, *read_);
  if (is_write) return Verdict::kAllowed;
  if (is_read) return needed == Scope::kRead ? Verdict::kAllowed : Verdict::kForbidden;
  return Verdict::kUnauthenticated;
}

CorsPolicy::CorsPolicy(std::vector<std::string> allowed)
    : allowed_(std::move(allowed)), any_(std::find(allowed_.begin(), allowed_.end(), "*") != allowed_.end()) {}

std::vector<std::pair<std::string, std::string>> CorsPolicy::Headers(const std::string& origin) const {
  std::vector<std::pair<std::string, std::string>> out;
  const bool listed = !origin.empty() && std::find(allowed_.begin(), allowed_.end(), origin) != allowed_.end();
  if (any_) {
    out.emplace_back("Access-Control-Allow-Origin", "*");
  } else if (listed) {
    out.emplace_back("Access-Control-Allow-Origin", origin);
  }
  if (any_ || listed) {
    out.emplace_back("Access-Control-Expose-Headers", "Content-Range, Content-Length, ETag, Location, Accept-Ranges");
  }
  // The answer depends on the Origin asked from: caches must key on it.
  if (!any_) out.emplace_back("Vary", "Origin");
  return out;
}

}  // namespace pointdag::server
