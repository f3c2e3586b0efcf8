#include "pointdag/read/las_reader.h"

#include <cmath>
#include <string>

#include "pointdag/read/byte_io.h"

namespace pointdag {
namespace {

constexpr size_t kHeaderSize12 = 227;
constexpr size_t kHeaderSize14 = 375;
constexpr size_t kVlrHeaderSize = 54;
constexpr size_t kEvlrHeaderSize = 60;

// Minimum record length of each point data record format 0-10 (LAS 1.4 R15, table 7 onwards).
constexpr uint32_t kMinRecordLength[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
// Byte offset of the red channel inside the record; 0 for formats without color.
constexpr uint32_t kRgbOffset[] = {0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30};

std::string Num(uint64_t v) { return std::to_string(v); }

Status ReadAt(std::FILE* f, uint64_t offset, void* out, size_t n, const char* what) {
  if (fseeko(f, static_cast<off_t>(offset), SEEK_SET) != 0 || std::fread(out, 1, n, f) != n) {
    return Truncated(std::string("file ends inside the ") + what);
  }
  return Status::Ok();
}

// Interprets one (E)VLR payload we care about; others are skipped.
Status ParseRecord(const std::string& user, uint16_t record_id, const std::vector<unsigned char>& data,
                   ScanInfo& info) {
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

}  // namespace

StatusOr<std::unique_ptr<ScanReader>> LasReader::Open(const std::filesystem::path& path) {
  std::error_code ec;
  const uint64_t file_size = std::filesystem::file_size(path, ec);
  if (ec) return IoError("cannot stat " + path.string() + ": " + ec.message());
  std::unique_ptr<LasReader> reader(new LasReader());
  reader->path_ = path.string();
  reader->file_ = std::fopen(reader->path_.c_str(), "rb");
  if (!reader->file_) return IoError("cannot open " + reader->path_);
  RETURN_IF_ERROR(reader->ParseHeader(file_size));
  RETURN_IF_ERROR(reader->Rewind());
  return std::unique_ptr<ScanReader>(std::move(reader));
}

LasReader::~LasReader() {
  if (file_) std::fclose(file_);
}

Status LasReader::ParseHeader(uint64_t file_size) {
  if (file_size < kHeaderSize12) {
    return Truncated("LAS file is " + Num(file_size) + " bytes, shorter than the 227-byte LAS header");
  }
  unsigned char h[kHeaderSize14] = {};
  const size_t head_bytes = static_cast<size_t>(std::min<uint64_t>(file_size, kHeaderSize14));
  RETURN_IF_ERROR(ReadAt(file_, 0, h, head_bytes, "LAS header"));
  if (std::memcmp(h, "LASF", 4) != 0) return Malformed("not a LAS file: missing 'LASF' signature");

  const int major = h[24], minor = h[25];
  if (major != 1 || minor > 4) {
    return Unsupported("LAS version " + Num(major) + "." + Num(minor) + " is not supported (1.0-1.4 are)");
  }
  info_.format = ScanFormat::kLas;
  info_.format_version = Num(major) + "." + Num(minor);

  const uint16_t header_size = LoadLE<uint16_t>(h + 94);
  point_data_offset_ = LoadLE<uint32_t>(h + 96);
  const uint32_t vlr_count = LoadLE<uint32_t>(h + 100);
  const uint8_t format_byte = h[104];
  record_length_ = LoadLE<uint16_t>(h + 105);

  if (format_byte & 0xC0) {
    return Unsupported(
        "this is a LAZ (compressed LAS) file; no LAZ decoder is packaged for this platform "
        "(Debian 12), so decompress it to LAS first (e.g. `pdal translate in.laz out.las`)");
  }
  if (format_byte > 10) return Unsupported("LAS point data record format " + Num(format_byte) + " is unknown (0-10 are)");
  info_.las_point_format = format_byte;
  const size_t min_header = minor >= 4 ? kHeaderSize14 : kHeaderSize12;
  if (header_size < min_header || header_size > file_size) {
    return Malformed("LAS header size " + Num(header_size) + " is invalid for LAS " + info_.format_version +
                     " in a file of " + Num(file_size) + " bytes");
  }
  if (point_data_offset_ < header_size || point_data_offset_ > file_size) {
    return Malformed("offset to point data " + Num(point_data_offset_) + " lies outside the file (header " +
                     Num(header_size) + " bytes, file " + Num(file_size) + " bytes)");
  }
  if (record_length_ < kMinRecordLength[format_byte]) {
    return Malformed("point record length " + Num(record_length_) + " is smaller than the " +
                     Num(kMinRecordLength[format_byte]) + " bytes point format " + Num(format_byte) + " needs");
  }
  rgb_offset_ = kRgbOffset[format_byte];
  info_.has_color = rgb_offset_ != 0;
  info_.stored_color_bits = 16;

  uint64_t count = LoadLE<uint32_t>(h + 107);
  uint64_t evlr_start = 0;
  uint32_t evlr_count = 0;
  if (minor >= 4) {
    const uint64_t count64 = LoadLE<uint64_t>(h + 247);
    if (count64 != 0) count = count64;
    evlr_start = LoadLE<uint64_t>(h + 235);
    evlr_count = LoadLE<uint32_t>(h + 243);
  }
  info_.point_count = count;

  for (int axis = 0; axis < 3; ++axis) {
    scale_[axis] = LoadLE<double>(h + 131 + 8 * axis);
    offset_[axis] = LoadLE<double>(h + 155 + 8 * axis);
    if (!std::isfinite(scale_[axis]) || scale_[axis] == 0.0 || !std::isfinite(offset_[axis])) {
      return Malformed("LAS scale/offset of axis " + std::string(1, "xyz"[axis]) + " is zero or not finite");
    }
  }
  Bounds hb;
  for (int axis = 0; axis < 3; ++axis) {
    hb.max[axis] = LoadLE<double>(h + 179 + 16 * axis);
    hb.min[axis] = LoadLE<double>(h + 187 + 16 * axis);
  }
  info_.header_bounds = hb;

  // Point data must fit between its offset and the EVLRs (or the end of the file).
  const uint64_t data_end = (evlr_count > 0 && evlr_start >= point_data_offset_ && evlr_start <= file_size)
                                ? evlr_start
                                : file_size;
  const uint64_t available = (data_end - point_data_offset_) / record_length_;
  if (count == 0) return Malformed("LAS header declares zero points");
  if (count > available) {
    return Truncated("LAS header declares " + Num(count) + " points of " + Num(record_length_) +
                     " bytes but the file holds only " + Num(available) + " complete records");
  }

  // VLRs live between the header and the point data.
  if (uint64_t{vlr_count} * kVlrHeaderSize > point_data_offset_ - header_size) {
    return Malformed("LAS header declares " + Num(vlr_count) + " VLRs, more than fit before the point data");
  }
  uint64_t pos = header_size;
  for (uint32_t i = 0; i < vlr_count; ++i) {
    unsigned char vh[kVlrHeaderSize];
    if (pos + kVlrHeaderSize > point_data_offset_) return Malformed("VLR " + Num(i) + " overruns the point data");
    RETURN_IF_ERROR(ReadAt(file_, pos, vh, kVlrHeaderSize, "VLR header"));
    const uint16_t length = LoadLE<uint16_t>(vh + 20);
    if (pos + kVlrHeaderSize + length > point_data_offset_) {
      return Malformed("VLR " + Num(i) + " of " + Num(length) + " bytes overruns the point data");
    }
    std::vector<unsigned char> data(length);
    RETURN_IF_ERROR(ReadAt(file_, pos + kVlrHeaderSize, data.data(), length, "VLR payload"));
    RETURN_IF_ERROR(ParseRecord(FixedString(vh + 2, 16), LoadLE<uint16_t>(vh + 18), data, info_));
    pos += kVlrHeaderSize + length;
  }

  // LAS 1.4 extended VLRs follow the point data; WKT often lives there.
  if (evlr_count > 0) {
    if (evlr_start < point_data_offset_ + count * record_length_ || evlr_start > file_size) {
      return Malformed("EVLR start " + Num(evlr_start) + " lies inside the point data or past the file end");
    }
    if (uint64_t{evlr_count} * kEvlrHeaderSize > file_size - evlr_start) {
      return Malformed("LAS header declares " + Num(evlr_count) + " EVLRs, more than fit in the file");
    }
    pos = evlr_start;
    for (uint32_t i = 0; i < evlr_count; ++i) {
      unsigned char eh[kEvlrHeaderSize];
      RETURN_IF_ERROR(ReadAt(file_, pos, eh, kEvlrHeaderSize, "EVLR header"));
      const uint64_t length = LoadLE<uint64_t>(eh + 20);
      if (length > file_size - pos - kEvlrHeaderSize) {
        return Malformed("EVLR " + Num(i) + " of " + Num(length) + " bytes overruns the file");
      }
      const std::string user = FixedString(eh + 2, 16);
      const uint16_t record_id = LoadLE<uint16_t>(eh + 18);
      if (user == "LASF_Projection") {  // only projection records are read; waveforms can be huge
        std::vector<unsigned char> data(length);
        RETURN_IF_ERROR(ReadAt(file_, pos + kEvlrHeaderSize, data.data(), data.size(), "EVLR payload"));
        RETURN_IF_ERROR(ParseRecord(user, record_id, data, info_));
      }
      pos += kEvlrHeaderSize + length;
    }
  }
  return Status::Ok();
}

Status LasReader::Rewind() {
  next_point_ = 0;
  if (fseeko(file_, static_cast<off_t>(point_data_offset_), SEEK_SET) != 0) {
    return IoError("cannot seek to the point data of " + path_);
  }
  return Status::Ok();
}

StatusOr<size_t> LasReader::Read(PointBatch& batch, size_t max_points) {
  batch.clear();
  const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, info_.point_count - next_point_));
  if (n == 0) return size_t{0};
  buffer_.resize(n * record_length_);
  if (std::fread(buffer_.data(), record_length_, n, file_) != n) {
    return Truncated("LAS point data ends early, at point " + Num(next_point_) + " of " + Num(info_.point_count));
  }
  batch.xyz.resize(n);
  if (info_.has_color) batch.rgb.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const unsigned char* rec = buffer_.data() + i * record_length_;
    auto& p = batch.xyz[i];
    for (int axis = 0; axis < 3; ++axis) {
      p[axis] = LoadLE<int32_t>(rec + 4 * axis) * scale_[axis] + offset_[axis];
    }
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      return Malformed("point " + Num(next_point_ + i) + " has a coordinate that is not finite");
    }
    if (info_.has_color) {
      auto& c = batch.rgb[i];
      for (int ch = 0; ch < 3; ++ch) {
        c[ch] = LoadLE<uint16_t>(rec + rgb_offset_ + 2 * ch);
        max_color_seen_ = std::max(max_color_seen_, c[ch]);
      }
    }
  }
  next_point_ += n;
  return n;
}

}  // namespace pointdag
