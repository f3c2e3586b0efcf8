// CheckPcdHeader (ply_pcd_header.h): the PCD half of our header check.
#include <algorithm>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "pointdag/read/header_text.h"
#include "pointdag/read/ply_pcd_header.h"

namespace pointdag {
namespace {

using header_text::IsFiniteNumber;
using header_text::Lines;
using header_text::ParseUnsigned;
using header_text::Quote;
using header_text::Tokens;

// The header lines in the order the PCD specification requires them.
constexpr const char* kKeywords[] = {"VERSION", "FIELDS", "SIZE", "TYPE", "COUNT",
                                     "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
enum Keyword { kVersion, kFields, kSize, kType, kCount, kWidth, kHeight, kViewpoint, kPoints, kData };
constexpr bool kOptional[] = {true, false, false, false, true, false, false, true, false, false};

// LZF's longest back reference is 3 bytes that expand to 264: no payload grows more than this.
constexpr uint64_t kLzfMaxExpansion = 88;

class PcdHeaderParser {
 public:
  explicit PcdHeaderParser(const header_text::Head& head) : head_(head) {}

  StatusOr<CheckedHeader> Parse() {
    Lines lines(head_, 0, 0, '\n', 0, "PCD");
    std::string_view line;
    int last = -1;
    while (last != kData) {
      ASSIGN_OR_RETURN(bool more, lines.Next(line));
      if (!more) return lines.Unterminated("DATA");
      if (line.empty() || line.front() == '#') continue;  // blank lines and comments, as PCL skips them
      const std::vector<std::string_view> t = Tokens(line);
      where_ = "PCD header line " + std::to_string(lines.number());
      const auto* kw = std::find(std::begin(kKeywords), std::end(kKeywords), t[0]);
      if (kw == std::end(kKeywords)) {
        return Malformed(where_ + ": unknown keyword " + Quote(t[0]) +
                         " (a PCD header holds VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA)");
      }
      const int k = static_cast<int>(kw - std::begin(kKeywords));
      if (k <= last) {
        return Malformed(where_ + ": " + kKeywords[k] + " comes after " + kKeywords[last] +
                         "; PCD requires the order VERSION FIELDS SIZE TYPE COUNT WIDTH HEIGHT VIEWPOINT POINTS DATA");
      }
      for (int skipped = last + 1; skipped < k; ++skipped) {
        if (!kOptional[skipped]) {
          return Malformed(where_ + ": " + kKeywords[k] + " before the mandatory " + kKeywords[skipped] + " line");
        }
      }
      if (k > kCount && counts_.empty()) counts_.assign(fields_.size(), 1);  // COUNT defaults to 1
      RETURN_IF_ERROR(ParseLine(static_cast<Keyword>(k), t));
      last = k;
    }
    body_offset_ = lines.offset();
    return Finish();
  }

 private:
  // A per-field line (SIZE, TYPE, COUNT) must list one value per field.
  Status CheckPerField(const std::vector<std::string_view>& t) const {
    if (t.size() - 1 != fields_.size()) {
      return Malformed(where_ + ": " + std::string(t[0]) + " lists " + std::to_string(t.size() - 1) +
                       " values for " + std::to_string(fields_.size()) + " FIELDS");
    }
    return Status::Ok();
  }

  StatusOr<uint64_t> Count(std::string_view token, const char* what) const {
    const auto v = ParseUnsigned(token);
    if (!v) return Malformed(where_ + ": " + what + " " + Quote(token) + " is not a non-negative integer");
    return *v;
  }

  Status ParseLine(Keyword k, const std::vector<std::string_view>& t) {
    switch (k) {
      case kVersion:
        if (t.size() != 2) return Malformed(where_ + ": VERSION takes one value");
        return Status::Ok();
      case kFields:
        if (t.size() < 2) return Malformed(where_ + ": FIELDS names no field");
        if (t.size() - 1 > kMaxFields) {
          return ResourceLimit(where_ + ": " + std::to_string(t.size() - 1) + " FIELDS, more than the " +
                               std::to_string(kMaxFields) + " allowed");
        }
        fields_.assign(t.begin() + 1, t.end());
        return Status::Ok();
      case kSize:
        RETURN_IF_ERROR(CheckPerField(t));
        for (size_t i = 1; i < t.size(); ++i) {
          ASSIGN_OR_RETURN(uint64_t size, Count(t[i], "SIZE"));
          if (size != 1 && size != 2 && size != 4 && size != 8) {
            return Malformed(where_ + ": SIZE " + std::to_string(size) + " of field " + Quote(fields_[i - 1]) +
                             " is not 1, 2, 4 or 8");
          }
          sizes_.push_back(size);
        }
        return Status::Ok();
      case kType:
        RETURN_IF_ERROR(CheckPerField(t));
        for (size_t i = 1; i < t.size(); ++i) {
          if (t[i] != "I" && t[i] != "U" && t[i] != "F") {
            return Unsupported(where_ + ": TYPE " + Quote(t[i]) + " of field " + Quote(fields_[i - 1]) +
                               " is not supported (I, U or F)");
          }
          if (t[i] == "F" && sizes_[i - 1] != 4 && sizes_[i - 1] != 8) {
            return Malformed(where_ + ": field " + Quote(fields_[i - 1]) + " is a float of SIZE " +
                             std::to_string(sizes_[i - 1]) + " (4 or 8)");
          }
        }
        return Status::Ok();
      case kCount:
        RETURN_IF_ERROR(CheckPerField(t));
        for (size_t i = 1; i < t.size(); ++i) {
          ASSIGN_OR_RETURN(uint64_t count, Count(t[i], "COUNT"));
          if (count == 0) return Malformed(where_ + ": COUNT of field " + Quote(fields_[i - 1]) + " is zero");
          if (count > kMaxFieldCount) {
            return ResourceLimit(where_ + ": COUNT " + std::string(t[i]) + " of field " + Quote(fields_[i - 1]) +
                                 " is more than the " + std::to_string(kMaxFieldCount) + " allowed");
          }
          counts_.push_back(count);
        }
        return Status::Ok();
      case kWidth:
      case kHeight:
      case kPoints: {
        if (t.size() != 2) return Malformed(where_ + ": " + std::string(t[0]) + " takes one value");
        ASSIGN_OR_RETURN(uint64_t v, Count(t[1], kKeywords[k]));
        if (v > kMaxPoints) {
          return ResourceLimit(where_ + ": " + std::string(t[0]) + " " + std::string(t[1]) + " is more than the " +
                               std::to_string(kMaxPoints) + " allowed");
        }
        (k == kWidth ? width_ : k == kHeight ? height_ : points_) = v;
        return Status::Ok();
      }
      case kViewpoint:
        if (t.size() != 8 || !std::all_of(t.begin() + 1, t.end(), IsFiniteNumber)) {
          return Malformed(where_ + ": VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
        }
        return Status::Ok();
      case kData:
        if (t.size() != 2 || (t[1] != "ascii" && t[1] != "binary" && t[1] != "binary_compressed")) {
          return Malformed(where_ + ": DATA must be ascii, binary or binary_compressed");
        }
        encoding_ = std::string(t[1]);
        return Status::Ok();
    }
    return Internal("unhandled PCD keyword");
  }

  StatusOr<CheckedHeader> Finish() {
    for (const char* axis : {"x", "y", "z"}) {
      if (std::find(fields_.begin(), fields_.end(), axis) == fields_.end()) {
        return Malformed(std::string("PCD file has no '") + axis + "' field");
      }
    }
    for (size_t i = 0; i < fields_.size(); ++i) {
      record_bytes_ += sizes_[i] * counts_[i];
      values_ += counts_[i];
    }
    if (record_bytes_ > kMaxRecordBytes) {
      return ResourceLimit("PCD points of " + std::to_string(record_bytes_) + " bytes, more than the " +
                           std::to_string(kMaxRecordBytes) + " allowed");
    }
    if (width_ * height_ != points_) {
      return Malformed("PCD WIDTH × HEIGHT (" + std::to_string(width_) + " × " + std::to_string(height_) +
                       ") is not POINTS (" + std::to_string(points_) + ")");
    }
    if (points_ == 0) return Malformed("PCD header declares zero points");
    RETURN_IF_ERROR(CheckBodyStart());
    RETURN_IF_ERROR(CheckBodySize());
    return CheckedHeader{points_, encoding_, 0, {}};
  }

  // PCL reads on after DATA as long as lines are blank, comments or start with a header keyword
  // (by prefix), and would take such a line's numbers over ours: refuse a body that begins so.
  Status CheckBodyStart() const {
    const std::string_view body = std::string_view(head_.bytes).substr(body_offset_);
    const bool head_is_whole_file = head_.bytes.size() == head_.file_size;
    size_t pos = 0;
    while (pos < body.size()) {
      size_t end = body.find('\n', pos);
      if (end == std::string_view::npos) end = body.size();
      const size_t line_start = pos;
      const std::string_view line = body.substr(pos, end - pos);
      pos = end + 1;
      if (line.empty()) continue;
      const size_t start = line.find_first_not_of(" \t\n\v\f\r");
      if (!head_is_whole_file && (start == std::string_view::npos || line_start + start + 16 > body.size())) break;
      if (start == std::string_view::npos) return Status::Ok();
      const std::string_view first = line.substr(start, line.find_first_of(" \t\n\v\f\r", start) - start);
      const bool header_like = first.front() == '#' || std::any_of(std::begin(kKeywords), std::end(kKeywords),
                                                                  [&](const char* kw) { return first.starts_with(kw); }) ||
                               first.starts_with("COLUMNS");
      if (header_like) {
        return Malformed("PCD data begins with " + Quote(first) + ", which reads as one more header line");
      }
      return Status::Ok();
    }
    if (head_is_whole_file) return Status::Ok();
    return Malformed("PCD data begins with over " + std::to_string(kMaxHeaderBytes) + " bytes of blank lines");
  }

  Status CheckBodySize() const {
    const uint64_t left = head_.file_size - body_offset_;
    if (encoding_ == "binary") {
      if (points_ > left / record_bytes_) {
        return Truncated("PCD header declares " + std::to_string(points_) + " points of " +
                         std::to_string(record_bytes_) + " bytes but the file holds only " +
                         std::to_string(left / record_bytes_) + " complete records");
      }
    } else if (encoding_ == "ascii") {
      const uint64_t fit = (left + 1) / (2 * values_);  // one character and a separator per value
      if (points_ > fit) {
        return Truncated("PCD header declares " + std::to_string(points_) + " points of " + std::to_string(values_) +
                         " values but its " + std::to_string(left) + " bytes of ASCII data can hold at most " +
                         std::to_string(fit));
      }
    } else {
      return CheckCompressedSizes(left);
    }
    return Status::Ok();
  }

  // binary_compressed: two little-endian uint32 (compressed, uncompressed size), then LZF bytes.
  Status CheckCompressedSizes(uint64_t left) const {
    if (left < 8 || body_offset_ + 8 > head_.bytes.size()) {
      return Truncated("binary_compressed PCD ends before its two size words");
    }
    uint32_t compressed, uncompressed;
    std::memcpy(&compressed, head_.bytes.data() + body_offset_, 4);
    std::memcpy(&uncompressed, head_.bytes.data() + body_offset_ + 4, 4);
    const uint64_t expected = points_ * record_bytes_;
    if (uncompressed != expected) {
      return Malformed("binary_compressed PCD says it unpacks to " + std::to_string(uncompressed) + " bytes, but " +
                       std::to_string(points_) + " points of " + std::to_string(record_bytes_) + " bytes are " +
                       std::to_string(expected));
    }
    if (compressed > left - 8) {
      return Truncated("binary_compressed PCD declares " + std::to_string(compressed) +
                       " compressed bytes but the file holds only " + std::to_string(left - 8));
    }
    if (compressed == 0 || uncompressed > uint64_t{compressed} * kLzfMaxExpansion) {
      return Malformed("binary_compressed PCD says " + std::to_string(compressed) + " compressed bytes unpack to " +
                       std::to_string(uncompressed) + ", more than LZF can expand them to");
    }
    return Status::Ok();
  }

  const header_text::Head& head_;
  std::string where_;
  std::vector<std::string> fields_;
  std::vector<uint64_t> sizes_, counts_;
  uint64_t width_ = 0, height_ = 0, points_ = 0;
  uint64_t record_bytes_ = 0, values_ = 0;
  std::string encoding_;
  size_t body_offset_ = 0;
};

}  // namespace

StatusOr<CheckedHeader> CheckPcdHeader(const std::filesystem::path& path) {
  // Room for the header and, after it, a binary_compressed file's two size words.
  ASSIGN_OR_RETURN(header_text::Head head, header_text::ReadHead(path, kMaxHeaderBytes + 8));
  return PcdHeaderParser(head).Parse();
}

}  // namespace pointdag
