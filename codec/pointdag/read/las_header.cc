#include "pointdag/read/las_header.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <string>

#include "pointdag/read/byte_io.h"

namespace pointdag {
namespace {

constexpr size_t kHeaderSize12 = 227;
constexpr size_t kHeaderSize14 = 375;
constexpr size_t kVlrHeaderSize = 54;
constexpr size_t kEvlrHeaderSize = 60;
constexpr uint16_t kLaszipRecordId = 22204;
constexpr uint16_t kCopcInfoRecordId = 1;

// Minimum record length of each point data record format 0-10 (LAS 1.4 R15, table 7 onwards).
constexpr uint32_t kMinRecordLength[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
// Byte offset of the red channel inside the record; 0 for formats without color.
constexpr uint32_t kRgbOffset[] = {0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30};

std::string Num(uint64_t v) { return std::to_string(v); }

// Interprets one (E)VLR payload we care about; others are skipped.
Status ParseRecord(const std::string& user, uint16_t record_id, std::vector<unsigned char> data, ScanInfo& info,
                   LasHeader& header) {
  if (user == "laszip encoded" && record_id == kLaszipRecordId) {
    header.laszip_vlr = std::move(data);
    return Status::Ok();
  }
  if (user == "copc" && record_id == kCopcInfoRecordId) {
    header.copc_info = std::move(data);
    return Status::Ok();
  }
  if (user != "LASF_Projection") return Status::Ok();
  if (record_id == 2112) {
    info.crs_wkt = FixedString(data.data(), data.size());
  } else if (record_id == 34735) {
    if (data.size() < 8) return Malformed("GeoKeyDirectory record is shorter than its 8-byte header");
    const uint16_t key_count = LoadLE<uint16_t>(data.data() + 6);
    if (8 + size_t{key_count} * 8 > data.size()) {
      return Malformed("GeoKeyDirectory declares " + Num(key_count) + " keys but holds room for " +
                       Num((data.size() - 8) / 8));
    }
    if (!info.geokeys) info.geokeys.emplace();
    for (size_t k = 0; k < key_count; ++k) {
      const unsigned char* p = data.data() + 8 + k * 8;
      info.geokeys->keys.push_back({LoadLE<uint16_t>(p), LoadLE<uint16_t>(p + 2), LoadLE<uint16_t>(p + 4),
                                    LoadLE<uint16_t>(p + 6)});
    }
  } else if (record_id == 34736) {
    if (!info.geokeys) info.geokeys.emplace();
    for (size_t i = 0; i + 8 <= data.size(); i += 8) info.geokeys->doubles.push_back(LoadLE<double>(data.data() + i));
  } else if (record_id == 34737) {
    if (!info.geokeys) info.geokeys.emplace();
    info.geokeys->ascii.assign(reinterpret_cast<const char*>(data.data()), data.size());
  }
  return Status::Ok();
}

Status ReadVlrs(std::FILE* file, uint32_t vlr_count, ScanInfo& info, LasHeader& header) {
  if (uint64_t{vlr_count} * kVlrHeaderSize > header.point_data_offset - header.header_size) {
    return Malformed("LAS header declares " + Num(vlr_count) + " VLRs, more than fit before the point data");
  }
  uint64_t pos = header.header_size;
  for (uint32_t i = 0; i < vlr_count; ++i) {
    unsigned char vh[kVlrHeaderSize];
    if (pos + kVlrHeaderSize > header.point_data_offset) return Malformed("VLR " + Num(i) + " overruns the point data");
    RETURN_IF_ERROR(ReadAt(file, pos, vh, kVlrHeaderSize, "VLR header"));
    const uint16_t length = LoadLE<uint16_t>(vh + 20);
    if (pos + kVlrHeaderSize + length > header.point_data_offset) {
      return Malformed("VLR " + Num(i) + " of " + Num(length) + " bytes overruns the point data");
    }
    std::vector<unsigned char> data(length);
    RETURN_IF_ERROR(ReadAt(file, pos + kVlrHeaderSize, data.data(), length, "VLR payload"));
    RETURN_IF_ERROR(ParseRecord(FixedString(vh + 2, 16), LoadLE<uint16_t>(vh + 18), std::move(data), info, header));
    pos += kVlrHeaderSize + length;
  }
  return Status::Ok();
}

// LAS 1.4 extended VLRs follow the point data; WKT often lives there. Only projection records are
// read: waveforms and COPC hierarchies can be huge.
Status ReadEvlrs(std::FILE* file, uint64_t evlr_start, uint32_t evlr_count, ScanInfo& info, LasHeader& header) {
  if (uint64_t{evlr_count} * kEvlrHeaderSize > header.file_size - evlr_start) {
    return Malformed("LAS header declares " + Num(evlr_count) + " EVLRs, more than fit in the file");
  }
  uint64_t pos = evlr_start;
  for (uint32_t i = 0; i < evlr_count; ++i) {
    unsigned char eh[kEvlrHeaderSize];
    RETURN_IF_ERROR(ReadAt(file, pos, eh, kEvlrHeaderSize, "EVLR header"));
    const uint64_t length = LoadLE<uint64_t>(eh + 20);
    if (length > header.file_size - pos - kEvlrHeaderSize) {
      return Malformed("EVLR " + Num(i) + " of " + Num(length) + " bytes overruns the file");
    }
    const std::string user = FixedString(eh + 2, 16);
    if (user == "LASF_Projection") {
      std::vector<unsigned char> data(length);
      RETURN_IF_ERROR(ReadAt(file, pos + kEvlrHeaderSize, data.data(), data.size(), "EVLR payload"));
      RETURN_IF_ERROR(ParseRecord(user, LoadLE<uint16_t>(eh + 18), std::move(data), info, header));
    }
    pos += kEvlrHeaderSize + length;
  }
  return Status::Ok();
}

}  // namespace

Status ReadAt(std::FILE* file, uint64_t offset, void* out, size_t n, const char* what) {
  if (fseeko(file, static_cast<off_t>(offset), SEEK_SET) != 0 || std::fread(out, 1, n, file) != n) {
    return Truncated(std::string("file ends inside the ") + what);
  }
  return Status::Ok();
}

StatusOr<LasHeader> ReadLasHeader(std::FILE* file, uint64_t file_size, ScanInfo& info, LasRecordLayout& layout) {
  if (file_size < kHeaderSize12) {
    return Truncated("LAS file is " + Num(file_size) + " bytes, shorter than the 227-byte LAS header");
  }
  unsigned char h[kHeaderSize14] = {};
  const size_t head_bytes = static_cast<size_t>(std::min<uint64_t>(file_size, kHeaderSize14));
  RETURN_IF_ERROR(ReadAt(file, 0, h, head_bytes, "LAS header"));
  if (std::memcmp(h, "LASF", 4) != 0) return Malformed("not a LAS file: missing 'LASF' signature");

  const int major = h[24], minor = h[25];
  if (major != 1 || minor > 4) {
    return Unsupported("LAS version " + Num(major) + "." + Num(minor) + " is not supported (1.0-1.4 are)");
  }
  LasHeader header;
  header.file_size = file_size;
  header.version_minor = minor;
  info.format = ScanFormat::kLas;
  info.format_version = Num(major) + "." + Num(minor);

  header.header_size = LoadLE<uint16_t>(h + 94);
  header.point_data_offset = LoadLE<uint32_t>(h + 96);
  const uint32_t vlr_count = LoadLE<uint32_t>(h + 100);
  const uint8_t format_byte = h[104];
  header.record_length = LoadLE<uint16_t>(h + 105);

  // LASzip sets bit 7 of the point format (bit 6 in its oldest files) to keep LAS-only readers out.
  header.compressed = (format_byte & 0xC0) != 0;
  const int format = format_byte & 0x3F;
  if (format > 10) return Unsupported("LAS point data record format " + Num(format) + " is unknown (0-10 are)");
  header.point_format = format;
  info.las_point_format = format;
  const size_t min_header = minor >= 4 ? kHeaderSize14 : kHeaderSize12;
  if (header.header_size < min_header || header.header_size > file_size) {
    return Malformed("LAS header size " + Num(header.header_size) + " is invalid for LAS " + info.format_version +
                     " in a file of " + Num(file_size) + " bytes");
  }
  if (header.point_data_offset < header.header_size || header.point_data_offset > file_size) {
    return Malformed("offset to point data " + Num(header.point_data_offset) + " lies outside the file (header " +
                     Num(header.header_size) + " bytes, file " + Num(file_size) + " bytes)");
  }
  if (header.record_length < kMinRecordLength[format]) {
    return Malformed("point record length " + Num(header.record_length) + " is smaller than the " +
                     Num(kMinRecordLength[format]) + " bytes point format " + Num(format) + " needs");
  }
  layout.record_length = header.record_length;
  layout.rgb_offset = kRgbOffset[format];
  info.has_color = layout.rgb_offset != 0;
  info.stored_color_bits = 16;

  uint64_t count = LoadLE<uint32_t>(h + 107);
  uint64_t evlr_start = 0;
  uint32_t evlr_count = 0;
  if (minor >= 4) {
    const uint64_t count64 = LoadLE<uint64_t>(h + 247);
    if (count64 != 0) count = count64;
    evlr_start = LoadLE<uint64_t>(h + 235);
    evlr_count = LoadLE<uint32_t>(h + 243);
  }
  header.point_count = count;
  info.point_count = count;

  for (int axis = 0; axis < 3; ++axis) {
    layout.scale[axis] = LoadLE<double>(h + 131 + 8 * axis);
    layout.offset[axis] = LoadLE<double>(h + 155 + 8 * axis);
    if (!std::isfinite(layout.scale[axis]) || layout.scale[axis] == 0.0 || !std::isfinite(layout.offset[axis])) {
      return Malformed("LAS scale/offset of axis " + std::string(1, "xyz"[axis]) + " is zero or not finite");
    }
  }
  Bounds hb;
  for (int axis = 0; axis < 3; ++axis) {
    hb.max[axis] = LoadLE<double>(h + 179 + 16 * axis);
    hb.min[axis] = LoadLE<double>(h + 187 + 16 * axis);
  }
  info.header_bounds = hb;

  // Point data lies between its offset and the EVLRs (or the end of the file).
  const bool has_evlrs = evlr_count > 0;
  if (has_evlrs && (evlr_start < header.point_data_offset || evlr_start > file_size)) {
    return Malformed("EVLR start " + Num(evlr_start) + " lies before the point data or past the file end");
  }
  header.point_data_end = has_evlrs ? evlr_start : file_size;
  RETURN_IF_ERROR(ReadVlrs(file, vlr_count, info, header));
  if (has_evlrs) RETURN_IF_ERROR(ReadEvlrs(file, evlr_start, evlr_count, info, header));
  return header;
}

Status LasRecordLayout::Append(const unsigned char* records, size_t n, uint64_t first_index, PointBatch& batch,
                               uint16_t& max_color_seen) const {
  const size_t base = batch.xyz.size();
  batch.xyz.resize(base + n);
  if (rgb_offset != 0) batch.rgb.resize(base + n);
  return Decode(records, n, first_index, batch.xyz.data() + base, rgb_offset != 0 ? batch.rgb.data() + base : nullptr,
                max_color_seen);
}

Status LasRecordLayout::Decode(const unsigned char* records, size_t n, uint64_t first_index,
                               std::array<double, 3>* xyz, std::array<uint16_t, 3>* rgb,
                               uint16_t& max_color_seen) const {
  // Locals, not members or references: the stores to xyz and rgb cannot change them, so they stay
  // in registers (a uint16_t reference could alias an rgb channel and was reloaded every point).
  const std::array<double, 3> s = scale, o = offset;
  const size_t length = record_length;
  double nx = 0, ny = 0, nz = 0;  // sums of v * 0: ±0 while every v is finite, NaN after any other
  const unsigned char* rec = records;
  for (size_t i = 0; i < n; ++i, rec += length) {
    const double x = LoadLE<int32_t>(rec) * s[0] + o[0], y = LoadLE<int32_t>(rec + 4) * s[1] + o[1],
                 z = LoadLE<int32_t>(rec + 8) * s[2] + o[2];
    nx += x * 0.0, ny += y * 0.0, nz += z * 0.0;
    xyz[i] = {x, y, z};
  }
  if (!(nx + ny + nz == 0)) {
    size_t i = 0;
    while (std::isfinite(xyz[i][0]) && std::isfinite(xyz[i][1]) && std::isfinite(xyz[i][2])) ++i;
    return Malformed("point " + Num(first_index + i) + " has a coordinate that is not finite");
  }
  if (rgb) {
    const unsigned char* channels = records + rgb_offset;
    uint16_t max = max_color_seen;
    for (size_t i = 0; i < n; ++i, channels += length) {
      auto& c = rgb[i];
      for (int ch = 0; ch < 3; ++ch) {
        c[ch] = LoadLE<uint16_t>(channels + 2 * ch);
        max = std::max(max, c[ch]);
      }
    }
    max_color_seen = max;
  }
  return Status::Ok();
}

Status LasRecordLayout::Widen(const unsigned char* records, size_t n, uint64_t first_index, Bounds& bounds,
                              uint16_t& max_color_seen) const {
  if (n == 0) return Status::Ok();
  const size_t length = record_length;
  int32_t lx = INT32_MAX, ly = INT32_MAX, lz = INT32_MAX, hx = INT32_MIN, hy = INT32_MIN, hz = INT32_MIN;
  const unsigned char* rec = records;
  for (size_t i = 0; i < n; ++i, rec += length) {
    const int32_t x = LoadLE<int32_t>(rec), y = LoadLE<int32_t>(rec + 4), z = LoadLE<int32_t>(rec + 8);
    lx = std::min(lx, x), ly = std::min(ly, y), lz = std::min(lz, z);
    hx = std::max(hx, x), hy = std::max(hy, y), hz = std::max(hz, z);
  }
  const int32_t lo[3] = {lx, ly, lz}, hi[3] = {hx, hy, hz};
  std::array<double, 3> low, high;
  for (int axis = 0; axis < 3; ++axis) {
    low[axis] = lo[axis] * scale[axis] + offset[axis];
    high[axis] = hi[axis] * scale[axis] + offset[axis];
    if (scale[axis] < 0) std::swap(low[axis], high[axis]);
    if (!std::isfinite(low[axis]) || !std::isfinite(high[axis])) {
      // Some point overflows: Decode names the first.
      std::vector<std::array<double, 3>> xyz(n);
      RETURN_IF_ERROR(Decode(records, n, first_index, xyz.data(), nullptr, max_color_seen));
      return Internal("LAS bounds overflow but every point is finite");
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    bounds.min[axis] = std::min(bounds.min[axis], low[axis]);
    bounds.max[axis] = std::max(bounds.max[axis], high[axis]);
  }
  if (rgb_offset != 0) {
    uint16_t max = max_color_seen;
    rec = records + rgb_offset;
    for (size_t i = 0; i < n; ++i, rec += length) {
      max = std::max({max, LoadLE<uint16_t>(rec), LoadLE<uint16_t>(rec + 2), LoadLE<uint16_t>(rec + 4)});
    }
    max_color_seen = max;
  }
  return Status::Ok();
}

}  // namespace pointdag
