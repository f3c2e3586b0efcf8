#include "pointdag/read/header_text.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "pointdag/read/ply_pcd_header.h"

namespace pointdag::header_text {

StatusOr<Head> ReadHead(const std::filesystem::path& path, size_t max_bytes) {
  std::error_code ec;
  Head head;
  head.file_size = std::filesystem::file_size(path, ec);
  if (ec) return IoError("cannot stat " + path.string() + ": " + ec.message());
  head.bytes.resize(static_cast<size_t>(std::min<uint64_t>(head.file_size, max_bytes)));
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return IoError("cannot open " + path.string());
  const size_t got = std::fread(head.bytes.data(), 1, head.bytes.size(), f);
  std::fclose(f);
  if (got != head.bytes.size()) return IoError("cannot read the header of " + path.string());
  return head;
}

StatusOr<bool> Lines::Next(std::string_view& line) {
  const std::string_view text(head_.bytes);
  if (pos_ >= text.size()) return false;
  const size_t end = text.find(delim_, pos_);
  const size_t length = (end == std::string_view::npos ? text.size() : end) - pos_;
  if (length > kMaxLineBytes) {
    return Malformed(std::string(format_) + " header line " + std::to_string(number_ + 1) + " is longer than " +
                     std::to_string(kMaxLineBytes) + " bytes");
  }
  if (end == std::string_view::npos) return false;
  line = text.substr(pos_, length);
  pos_ = end + 1 + skip_after_;
  ++number_;
  if (!line.empty() && line.back() == '\r') {
    line.remove_suffix(1);
    // PCL ends a PCD header at such a line instead of skipping it as a blank one.
    if (line.empty()) return Malformed(std::string(format_) + " header line " + std::to_string(number_) + " is a bare CR");
  }
  if (!line.empty() && (line.front() == ' ' || line.front() == '\t')) {
    return Malformed(std::string(format_) + " header line " + std::to_string(number_) + " starts with white space");
  }
  for (char c : line) {
    const auto u = static_cast<unsigned char>(c);
    if ((u < 0x20 && c != '\t') || u == 0x7F) {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "0x%02X", u);
      return Malformed(std::string(format_) + " header line " + std::to_string(number_) + " holds the control byte " +
                       hex + "; this is not a text header");
    }
  }
  return true;
}

Status Lines::Unterminated(const char* what) const {
  if (head_.bytes.size() < head_.file_size) {
    return Malformed(std::string(format_) + " header has no " + what + " line within its first " +
                     std::to_string(kMaxHeaderBytes) + " bytes");
  }
  return Malformed(std::string(format_) + " file ends before its header's " + what + " line");
}

std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t pos = 0;
  while (pos < line.size()) {
    const size_t start = line.find_first_not_of(" \t", pos);
    if (start == std::string_view::npos) break;
    size_t end = line.find_first_of(" \t", start);
    if (end == std::string_view::npos) end = line.size();
    tokens.push_back(line.substr(start, end - start));
    pos = end;
  }
  return tokens;
}

std::optional<uint64_t> ParseUnsigned(std::string_view token) {
  if (token.empty() || token.size() > 20) return std::nullopt;
  uint64_t value = 0;
  for (char c : token) {
    if (c < '0' || c > '9') return std::nullopt;
    const uint64_t digit = static_cast<uint64_t>(c - '0');
    if (value > (UINT64_MAX - digit) / 10) return std::nullopt;
    value = value * 10 + digit;
  }
  return value;
}

bool IsFiniteNumber(std::string_view token) {
  if (token.empty() || token.size() > 64) return false;
  const std::string text(token);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(v);
}

std::string Quote(std::string_view token) {
  constexpr size_t kShown = 40;
  if (token.size() <= kShown) return "'" + std::string(token) + "'";
  return "'" + std::string(token.substr(0, kShown)) + "...'";
}

}  // namespace pointdag::header_text
