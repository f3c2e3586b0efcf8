#include "pointdag/read/ply_reader.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <string_view>

#include "pointdag/read/byte_io.h"

namespace pointdag {
namespace {

size_t TypeSize(std::string_view type) {
  if (type == "char" || type == "int8" || type == "uchar" || type == "uint8") return 1;
  if (type == "short" || type == "int16" || type == "ushort" || type == "uint16") return 2;
  if (type == "double" || type == "float64") return 8;
  return 4;  // int, uint, float and their sized names (CheckPlyHeader knows no other)
}

bool IsColorName(std::string_view name) {
  return name == "rgb" || name == "rgba" || name == "red" || name == "green" || name == "blue" || name == "r" ||
         name == "g" || name == "b" || name == "alpha" || name.starts_with("diffuse_");
}

// Byte offsets of what the reader takes from a record, when the layout is the plain one.
struct Layout {
  size_t record = 0;
  size_t xyz[3] = {0, 0, 0};
  bool xyz_double[3] = {false, false, false};
  std::optional<size_t> rgb[3];
};

std::optional<Layout> PlainLayout(const CheckedHeader& header) {
  if (header.encoding != "binary_little_endian" || std::endian::native != std::endian::little ||
      header.first_vertex_scalars.empty()) {
    return std::nullopt;
  }
  Layout layout;
  bool has_xyz[3] = {false, false, false};
  constexpr std::string_view kAxes[3] = {"x", "y", "z"}, kChannels[3] = {"red", "green", "blue"};
  for (const PlyScalar& p : header.first_vertex_scalars) {
    for (int a = 0; a < 3; ++a) {
      if (p.name != kAxes[a]) continue;
      if (p.type != "float" && p.type != "float32" && p.type != "double" && p.type != "float64") return std::nullopt;
      layout.xyz[a] = layout.record;
      layout.xyz_double[a] = TypeSize(p.type) == 8;
      has_xyz[a] = true;
    }
    if (IsColorName(p.name)) {
      int ch = 0;
      while (ch < 3 && p.name != kChannels[ch]) ++ch;
      if (ch == 3 || (p.type != "uchar" && p.type != "uint8")) return std::nullopt;
      layout.rgb[ch] = layout.record;
    }
    layout.record += TypeSize(p.type);
  }
  const bool colors = layout.rgb[0] && layout.rgb[1] && layout.rgb[2];
  if (!(has_xyz[0] && has_xyz[1] && has_xyz[2]) || (!colors && (layout.rgb[0] || layout.rgb[1] || layout.rgb[2]))) {
    return std::nullopt;
  }
  return layout;
}

class PlainPlyReader final : public ScanReader {
 public:
  PlainPlyReader(std::FILE* file, const CheckedHeader& header, const Layout& layout)
      : file_(file), body_offset_(header.body_offset), layout_(layout) {
    info_.format = ScanFormat::kPly;
    info_.format_version = header.encoding;
    info_.point_count = header.points;
    info_.has_color = layout.rgb[0].has_value();
    info_.stored_color_bits = 8;
  }
  ~PlainPlyReader() override { std::fclose(file_); }

  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override {
    const StatusOr<size_t> n = Fill(max_points);
    if (!n.ok()) {
      batch.clear();
      return n.status();
    }
    RETURN_IF_ERROR(Decode(*n, batch));
    next_ += *n;
    return *n;
  }

  StatusOr<size_t> ReadBounds(Bounds& bounds, size_t max_points, PointBatch& scratch) override {
    const bool doubles = layout_.xyz_double[0] && layout_.xyz_double[1] && layout_.xyz_double[2];
    const bool floats = !layout_.xyz_double[0] && !layout_.xyz_double[1] && !layout_.xyz_double[2];
    if (!doubles && !floats) return ScanReader::ReadBounds(bounds, max_points, scratch);
    ASSIGN_OR_RETURN(const size_t n, Fill(max_points));
    if (!(doubles ? WidenBounds<double>(n, bounds) : WidenBounds<float>(n, bounds))) {
      return Decode(n, scratch);  // Decode names the first point that is not finite
    }
    if (info_.has_color) {
      const size_t record = layout_.record, r = *layout_.rgb[0], g = *layout_.rgb[1], b = *layout_.rgb[2];
      const unsigned char* at = buffer_.data();
      unsigned char max = 0;
      for (size_t i = 0; i < n; ++i, at += record) max = std::max({max, at[r], at[g], at[b]});
      max_color_seen_ = std::max<uint16_t>(max_color_seen_, max);
    }
    next_ += n;
    return n;
  }

  Status Rewind() override {
    if (std::fseek(file_, static_cast<long>(body_offset_), SEEK_SET) != 0) return IoError("cannot seek in the PLY file");
    next_ = 0;
    return Status::Ok();
  }

 private:
  std::FILE* file_;
  uint64_t body_offset_;
  Layout layout_;
  uint64_t next_ = 0;
  std::vector<unsigned char> buffer_;

  // The next up to max_points records into buffer_; how many.
  StatusOr<size_t> Fill(size_t max_points) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, info_.point_count - next_));
    buffer_.resize(n * layout_.record);
    if (std::fread(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) {
      return Truncated("PLY data ends early, at point " + std::to_string(next_) + " of " + std::to_string(info_.point_count));
    }
    return n;
  }

  // buffer_'s n records as points; Malformed naming the first point that is not finite.
  Status Decode(size_t n, PointBatch& batch) {
    // Resized, not cleared: a batch of the last call's size is overwritten without being zero-filled first.
    batch.xyz.resize(n);
    batch.rgb.resize(info_.has_color ? n : 0);
    const bool finite = layout_.xyz_double[0] && layout_.xyz_double[1] && layout_.xyz_double[2]
                            ? DecodeXyz<double>(n, batch)
                        : !layout_.xyz_double[0] && !layout_.xyz_double[1] && !layout_.xyz_double[2]
                            ? DecodeXyz<float>(n, batch)
                            : DecodeMixedXyz(n, batch);
    if (!finite) {
      size_t i = 0;
      while (std::isfinite(batch.xyz[i][0]) && std::isfinite(batch.xyz[i][1]) && std::isfinite(batch.xyz[i][2])) ++i;
      return Malformed("point " + std::to_string(next_ + i) + " has a coordinate that is not finite");
    }
    if (info_.has_color) DecodeRgb(n, batch);
    return Status::Ok();
  }

  // Widens bounds by buffer_'s n records, all of one coordinate type: the extremes in that type
  // (its conversion to double is exact and keeps order), with ties kept first-seen as the double
  // comparisons on points do. False if a coordinate is not finite.
  template <class Coord>
  bool WidenBounds(size_t n, Bounds& bounds) const {
    if (n == 0) return true;
    const size_t record = layout_.record, ox = layout_.xyz[0], oy = layout_.xyz[1], oz = layout_.xyz[2];
    constexpr Coord inf = std::numeric_limits<Coord>::infinity();
    Coord lx = inf, ly = inf, lz = inf, hx = -inf, hy = -inf, hz = -inf;
    Coord nx = 0, ny = 0, nz = 0;  // sums of v * 0, as below
    const unsigned char* at = buffer_.data();
    for (size_t i = 0; i < n; ++i, at += record) {
      const Coord x = LoadLE<Coord>(at + ox), y = LoadLE<Coord>(at + oy), z = LoadLE<Coord>(at + oz);
      lx = std::min(lx, x), ly = std::min(ly, y), lz = std::min(lz, z);
      hx = std::max(hx, x), hy = std::max(hy, y), hz = std::max(hz, z);
      nx += x * Coord{0}, ny += y * Coord{0}, nz += z * Coord{0};
    }
    if (!(nx + ny + nz == 0)) return false;
    const double lo[3] = {lx, ly, lz}, hi[3] = {hx, hy, hz};
    for (int axis = 0; axis < 3; ++axis) {
      bounds.min[axis] = std::min(bounds.min[axis], lo[axis]);
      bounds.max[axis] = std::max(bounds.max[axis], hi[axis]);
    }
    return true;
  }

  // The loops below keep the layout in locals: stores to the batch cannot change them, so they stay
  // in registers. Each returns whether every coordinate is finite, the fixed-type ones from sums of
  // v * 0: ±0 for a finite v, NaN for an infinite or NaN one, which the sum keeps; one test a batch
  // instead of a test per value.
  template <class Coord>
  bool DecodeXyz(size_t n, PointBatch& batch) const {
    const size_t record = layout_.record, x = layout_.xyz[0], y = layout_.xyz[1], z = layout_.xyz[2];
    const unsigned char* at = buffer_.data();
    std::array<double, 3>* out = batch.xyz.data();
    Coord nx = 0, ny = 0, nz = 0;
    for (size_t i = 0; i < n; ++i, at += record) {
      const Coord vx = LoadLE<Coord>(at + x), vy = LoadLE<Coord>(at + y), vz = LoadLE<Coord>(at + z);
      nx += vx * Coord{0}, ny += vy * Coord{0}, nz += vz * Coord{0};
      out[i] = {vx, vy, vz};
    }
    return nx + ny + nz == 0;
  }

  bool DecodeMixedXyz(size_t n, PointBatch& batch) const {
    bool finite = true;
    for (size_t i = 0; i < n; ++i) {
      const unsigned char* record = buffer_.data() + i * layout_.record;
      for (int axis = 0; axis < 3; ++axis) {
        const unsigned char* at = record + layout_.xyz[axis];
        const double v = layout_.xyz_double[axis] ? LoadLE<double>(at) : LoadLE<float>(at);
        finite &= std::isfinite(v);
        batch.xyz[i][axis] = v;
      }
    }
    return finite;
  }

  void DecodeRgb(size_t n, PointBatch& batch) {
    const size_t record = layout_.record, r = *layout_.rgb[0], g = *layout_.rgb[1], b = *layout_.rgb[2];
    const unsigned char* at = buffer_.data();
    unsigned char max = 0;
    for (size_t i = 0; i < n; ++i, at += record) {
      batch.rgb[i] = {at[r], at[g], at[b]};
      max = std::max({max, at[r], at[g], at[b]});
    }
    max_color_seen_ = std::max<uint16_t>(max_color_seen_, max);
  }
};

}  // namespace

StatusOr<std::unique_ptr<ScanReader>> OpenPlainPly(const std::filesystem::path& path, const CheckedHeader& header) {
  const std::optional<Layout> layout = PlainLayout(header);
  if (!layout) return std::unique_ptr<ScanReader>();
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) return IoError("cannot open " + path.string());
  auto reader = std::make_unique<PlainPlyReader>(file, header, *layout);
  RETURN_IF_ERROR(reader->Rewind());
  return std::unique_ptr<ScanReader>(std::move(reader));
}

}  // namespace pointdag
