// Line and number parsing shared by the PLY and PCD header checks (ply_pcd_header.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pointdag/status.h"

namespace pointdag::header_text {

// The first bytes of a file and its full size.
struct Head {
  std::string bytes;
  uint64_t file_size = 0;
};
StatusOr<Head> ReadHead(const std::filesystem::path& path, size_t max_bytes);

// Walks the lines of a header held in `head`. A line ends at `delim`; `skip_after` more bytes are
// skipped after it (PLY files whose lines end in CR LF use CR as delimiter and skip the LF, as PCL
// does). Lines come back without their end and without one trailing '\r'.
class Lines {
 public:
  // `lines_before`: lines already consumed before `start` (the PLY magic line).
  Lines(const Head& head, size_t start, size_t lines_before, char delim, size_t skip_after, const char* format)
      : head_(head), pos_(start), delim_(delim), skip_after_(skip_after), format_(format), number_(lines_before) {}

  // Sets `line` to the next line and returns true; false when the head holds no further complete
  // line. A line that is too long, starts with white space or holds a control byte is an error.
  StatusOr<bool> Next(std::string_view& line);
  size_t number() const { return number_; }  // 1-based number of the line last returned
  size_t offset() const { return pos_; }       // where the line after it starts
  // The error for a header that never reaches its last line (`what`: "end_header", "DATA").
  Status Unterminated(const char* what) const;

 private:
  const Head& head_;
  size_t pos_;
  char delim_;
  size_t skip_after_;
  const char* format_;
  size_t number_;
};

// Tokens separated by spaces and tabs.
std::vector<std::string_view> Tokens(std::string_view line);
// A plain decimal integer (digits only, no sign, no exponent); nullopt otherwise or on overflow.
std::optional<uint64_t> ParseUnsigned(std::string_view token);
// A finite decimal number as written by printf("%g") and friends.
bool IsFiniteNumber(std::string_view token);
// A token for an error message: quoted, cut to a readable length.
std::string Quote(std::string_view token);

}  // namespace pointdag::header_text
