// CheckPlyHeader (ply_pcd_header.h): the PLY half of our header check.
#include <algorithm>
#include <string>
#include <string_view>
#include <vector>

#include "pointdag/read/header_text.h"
#include "pointdag/read/ply_pcd_header.h"

namespace pointdag {
namespace {

using header_text::Lines;
using header_text::ParseUnsigned;
using header_text::Quote;
using header_text::Tokens;

// Byte size of a PLY scalar type by either of its names; 0 when unknown.
size_t ScalarSize(std::string_view type) {
  struct Named {
    const char* name;
    const char* old_name;
    size_t size;
  };
  static constexpr Named kTypes[] = {{"int8", "char", 1},   {"uint8", "uchar", 1},  {"int16", "short", 2},
                                     {"uint16", "ushort", 2}, {"int32", "int", 4},   {"uint32", "uint", 4},
                                     {"float32", "float", 4}, {"float64", "double", 8}};
  for (const Named& t : kTypes) {
    if (type == t.name || type == t.old_name) return t.size;
  }
  return 0;
}

// List lengths may only be unsigned (PCL's parser knows no other).
bool IsListSizeType(std::string_view type) {
  return type == "uint8" || type == "uchar" || type == "uint16" || type == "ushort" || type == "uint32" ||
         type == "uint";
}

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<std::string> properties;
  std::vector<std::string> scalar_types;  // parallel to properties while no list comes
  std::vector<std::string> lists;  // names of list properties
  uint64_t min_record_bytes = 0;   // binary: scalars plus each list's length word
};

class PlyHeaderParser {
 public:
  explicit PlyHeaderParser(const header_text::Head& head) : head_(head) {}

  StatusOr<CheckedHeader> Parse() {
    const std::string& b = head_.bytes;
    if (b.size() < 4 || b.compare(0, 3, "ply") != 0 || (b[3] != '\n' && b[3] != '\r')) {
      return Malformed("not a PLY file: it does not start with the line 'ply'");
    }
    const bool crlf = b[3] == '\r';  // then lines end in CR and the LF after each is skipped, as PCL does
    if (crlf && (b.size() < 5 || b[4] != '\n')) return Malformed("PLY header lines end in CR without LF");
    Lines lines(head_, crlf ? 5 : 4, 1, crlf ? '\r' : '\n', crlf ? 1 : 0, "PLY");
    std::string_view line;
    for (;;) {
      ASSIGN_OR_RETURN(bool more, lines.Next(line));
      if (!more) return lines.Unterminated("end_header");
      if (crlf && b[lines.offset() - 1] != '\n') {
        return Malformed("PLY header line " + std::to_string(lines.number()) + " ends in CR without LF");
      }
      const std::vector<std::string_view> t = Tokens(line);
      if (t.empty()) continue;  // blank lines are ignored, as PCL does
      where_ = "PLY header line " + std::to_string(lines.number());
      if (t[0] == "end_header") {
        if (t.size() != 1) return Malformed(where_ + ": end_header takes no arguments");
        body_offset_ = lines.offset();
        break;
      }
      RETURN_IF_ERROR(ParseLine(t));
    }
    return Finish();
  }

 private:
  Status ParseLine(const std::vector<std::string_view>& t) {
    if (t[0] == "comment") return Status::Ok();
    if (t[0] == "obj_info") return ParseObjInfo(t);
    if (t[0] == "format") return ParseFormat(t);
    if (encoding_.empty()) return Malformed(where_ + ": the format line must come before " + Quote(t[0]));
    if (t[0] == "element") return ParseElement(t);
    if (t[0] == "property") return ParseProperty(t);
    return Malformed(where_ + ": unknown keyword " + Quote(t[0]) +
                     " (a PLY header holds format, element, property, comment, obj_info and end_header lines)");
  }

  Status ParseFormat(const std::vector<std::string_view>& t) {
    if (!encoding_.empty()) return Malformed(where_ + ": a second format line");
    if (t.size() != 3) return Malformed(where_ + ": the format line must read 'format ENCODING 1.0'");
    if (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian") {
      return Malformed(where_ + ": unknown PLY format " + Quote(t[1]) +
                       " (ascii, binary_little_endian or binary_big_endian)");
    }
    if (t[2] != "1.0") return Unsupported(where_ + ": PLY version " + Quote(t[2]) + " is not supported (1.0 is)");
    encoding_ = std::string(t[1]);
    return Status::Ok();
  }

  // PCL takes obj_info num_cols / num_rows as the cloud's width and height and allocates their
  // product, so they must describe the vertices the file really has (checked in Finish()).
  Status ParseObjInfo(const std::vector<std::string_view>& t) {
    if (t.size() < 3 || (t[1] != "num_cols" && t[1] != "num_rows")) return Status::Ok();
    const auto v = ParseUnsigned(t[2]);
    if (!v || *v > 0x7FFFFFFF) {
      return Malformed(where_ + ": obj_info " + std::string(t[1]) + " needs a non-negative integer, not " + Quote(t[2]));
    }
    (t[1] == "num_cols" ? grid_width_ : grid_height_) = static_cast<uint32_t>(*v);
    return Status::Ok();
  }

  Status ParseElement(const std::vector<std::string_view>& t) {
    if (t.size() != 3) return Malformed(where_ + ": an element line must read 'element NAME COUNT'");
    const auto count = ParseUnsigned(t[2]);
    if (!count) return Malformed(where_ + ": element count " + Quote(t[2]) + " is not a non-negative integer");
    if (*count > kMaxPoints) {
      return ResourceLimit(where_ + ": element " + Quote(t[1]) + " declares " + std::string(t[2]) +
                           " instances, more than the " + std::to_string(kMaxPoints) + " allowed");
    }
    for (const Element& e : elements_) {
      if (e.name == t[1]) return Malformed(where_ + ": element " + Quote(t[1]) + " is declared twice");
    }
    if (t[1] == "range_grid") {
      return Unsupported(where_ + ": PLY range_grid elements (organised range scans) are not supported");
    }
    if (elements_.size() == kMaxPlyElements) {
      return ResourceLimit(where_ + ": more than " + std::to_string(kMaxPlyElements) + " elements");
    }
    elements_.push_back({std::string(t[1]), *count, {}, {}, {}, 0});
    if (t[1] == "vertex" && (grid_width_ == 0 || grid_height_ == 0)) {  // as PCL sizes the cloud
      grid_width_ = static_cast<uint32_t>(*count);
      grid_height_ = 1;
    }
    return Status::Ok();
  }

  Status ParseProperty(const std::vector<std::string_view>& t) {
    if (elements_.empty()) return Malformed(where_ + ": a property before any element");
    Element& e = elements_.back();
    const bool list = t.size() >= 2 && t[1] == "list";
    if (list ? t.size() != 5 : t.size() != 3) {
      return Malformed(where_ + ": a property line must read 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME'");
    }
    const std::string_view name = t.back();
    if (std::find(e.properties.begin(), e.properties.end(), name) != e.properties.end()) {
      return Malformed(where_ + ": property " + Quote(name) + " of element " + Quote(e.name) + " is declared twice");
    }
    if (e.properties.size() == kMaxFields) {
      return ResourceLimit(where_ + ": element " + Quote(e.name) + " has more than " + std::to_string(kMaxFields) +
                           " properties");
    }
    if (list) {
      if (!IsListSizeType(t[2])) return Malformed(where_ + ": list length type " + Quote(t[2]) + " is not uchar, ushort or uint");
      if (ScalarSize(t[3]) == 0) return Malformed(where_ + ": unknown PLY type " + Quote(t[3]));
      if (e.name == "vertex") {
        return Unsupported(where_ + ": vertex property " + Quote(name) +
                           " is a list; point clouds with per-vertex lists are not supported");
      }
      e.min_record_bytes += ScalarSize(t[2]);  // an empty list still stores its length
      e.lists.emplace_back(name);
    } else {
      const size_t size = ScalarSize(t[1]);
      if (size == 0) return Malformed(where_ + ": unknown PLY type " + Quote(t[1]));
      if (e.name == "vertex" && (t[1] == "uchar" || t[1] == "uint8")) RETURN_IF_ERROR(CheckColorOrder(name));
      e.min_record_bytes += size;
      e.scalar_types.emplace_back(t[1]);
    }
    e.properties.emplace_back(name);
    return Status::Ok();
  }

  // PCL packs uchar red, green and blue into one 4-byte rgb field, declared at red and written when
  // it reads blue: a blue without a red before it, or a second red or blue, makes PCL write past
  // the point and abort on an assertion (Debian's PCL keeps them).
  Status CheckColorOrder(std::string_view name) {
    const bool red = name == "red" || name == "diffuse_red";
    const bool blue = name == "blue" || name == "diffuse_blue";
    if ((red && uchar_reds_ > 0) || (blue && (uchar_reds_ == 0 || uchar_blues_ > 0))) {
      return Unsupported(where_ + ": uchar vertex colors must be one red, green, blue set with red before blue");
    }
    uchar_reds_ += red;
    uchar_blues_ += blue;
    return Status::Ok();
  }

  StatusOr<CheckedHeader> Finish() {
    if (encoding_.empty()) return Malformed("PLY header has no format line");
    const Element* vertex = nullptr;
    for (const Element& e : elements_) {
      if (e.name == "vertex") vertex = &e;
    }
    if (!vertex) return Malformed("PLY header declares no vertex element, so the file holds no points");
    for (const char* axis : {"x", "y", "z"}) {
      if (std::find(vertex->properties.begin(), vertex->properties.end(), axis) == vertex->properties.end()) {
        return Malformed(std::string("PLY vertex element has no '") + axis + "' property");
      }
    }
    if (uchar_reds_ != uchar_blues_) {
      return Unsupported("PLY uchar vertex colors must be one red, green, blue set with red before blue");
    }
    if (vertex->count == 0) return Malformed("PLY header declares zero vertices");
    if (uint64_t{grid_width_} * grid_height_ != vertex->count) {
      return Malformed("PLY obj_info num_cols × num_rows (" + std::to_string(grid_width_) + " × " +
                       std::to_string(grid_height_) + ") disagrees with the " + std::to_string(vertex->count) +
                       " vertices declared");
    }
    RETURN_IF_ERROR(CheckBodySize());
    CheckedHeader out{vertex->count, encoding_, body_offset_, {}};
    if (vertex == &elements_.front()) {
      for (size_t i = 0; i < vertex->properties.size(); ++i) out.first_vertex_scalars.push_back({vertex->properties[i], vertex->scalar_types[i]});
    }
    return out;
  }

  // Each element's instances must fit in what is left of the file: binary records need their
  // fixed bytes, ASCII lines at least two bytes per property (one character and a separator).
  Status CheckBodySize() const {
    uint64_t left = head_.file_size - body_offset_;
    const bool ascii = encoding_ == "ascii";
    for (const Element& e : elements_) {
      if (e.count == 0) continue;
      if (e.properties.empty()) {
        return Malformed("PLY element " + Quote(e.name) + " declares " + std::to_string(e.count) +
                         " instances but no properties");
      }
      const uint64_t per = ascii ? 2 * e.properties.size() : e.min_record_bytes;
      const uint64_t fit = ascii ? (left + 1) / per : left / per;  // the last ASCII line may lack its end
      const std::string what = e.name == "vertex" ? "points" : Quote(e.name) + " elements";
      if (e.count > fit) {
        if (ascii) {
          return Truncated("PLY header declares " + std::to_string(e.count) + " " + what + " of " +
                           std::to_string(e.properties.size()) + " values but the " + std::to_string(left) +
                           " bytes of ASCII data left can hold at most " + std::to_string(fit));
        }
        return Truncated("PLY header declares " + std::to_string(e.count) + " " + what + " of " +
                         (e.lists.empty() ? "" : "at least ") + std::to_string(per) +
                         " bytes but the file holds only " + std::to_string(fit) + " complete records");
      }
      left -= std::min(left, e.count * per);
    }
    return Status::Ok();
  }

  const header_text::Head& head_;
  std::string where_;
  std::string encoding_;
  std::vector<Element> elements_;
  uint32_t grid_width_ = 0, grid_height_ = 0;  // what PCL will size the cloud by
  int uchar_reds_ = 0, uchar_blues_ = 0;
  size_t body_offset_ = 0;
};

}  // namespace

StatusOr<CheckedHeader> CheckPlyHeader(const std::filesystem::path& path) {
  ASSIGN_OR_RETURN(header_text::Head head, header_text::ReadHead(path, kMaxHeaderBytes));
  return PlyHeaderParser(head).Parse();
}

}  // namespace pointdag
