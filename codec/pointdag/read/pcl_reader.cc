#include "pointdag/read/pcl_reader.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <cmath>
#include <cstring>
#include <optional>

#include "pointdag/read/ply_pcd_header.h"

namespace pointdag {
namespace {

// Reads element `i` of a field of any PCL scalar type as double.
double LoadField(const unsigned char* p, uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: { int8_t v; std::memcpy(&v, p, 1); return v; }
    case pcl::PCLPointField::UINT8: return *p;
    case pcl::PCLPointField::INT16: { int16_t v; std::memcpy(&v, p, 2); return v; }
    case pcl::PCLPointField::UINT16: { uint16_t v; std::memcpy(&v, p, 2); return v; }
    case pcl::PCLPointField::INT32: { int32_t v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::UINT32: { uint32_t v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::FLOAT32: { float v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::INT64: { int64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
    case pcl::PCLPointField::UINT64: { uint64_t v; std::memcpy(&v, p, 8); return static_cast<double>(v); }
    case pcl::PCLPointField::FLOAT64: { double v; std::memcpy(&v, p, 8); return v; }
    default: return std::nan("");
  }
}

bool IsFloatType(uint8_t datatype) {
  return datatype == pcl::PCLPointField::FLOAT32 || datatype == pcl::PCLPointField::FLOAT64;
}

class PclScanReader final : public ScanReader {
 public:
  Status Load(const std::filesystem::path& path, ScanFormat format) {
    // PCL sees no file our own header check has not accepted (ply_pcd_header.h).
    ASSIGN_OR_RETURN(const CheckedHeader header,
                     format == ScanFormat::kPly ? CheckPlyHeader(path) : CheckPcdHeader(path));
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // errors come back as Status, not stderr noise
    info_.format = format;
    info_.format_version = header.encoding;
    int version = 0;
    int result = -1;
    // PCL throws on some malformed headers; keep exceptions inside this module.
    try {
      if (format == ScanFormat::kPly) {
        pcl::PLYReader reader;
        Eigen::Vector4f origin;
        Eigen::Quaternionf orientation;
        result = reader.read(path.string(), cloud_, origin, orientation, version);
      } else {
        pcl::PCDReader reader;
        Eigen::Vector4f origin;
        Eigen::Quaternionf orientation;
        result = reader.read(path.string(), cloud_, origin, orientation, version);
      }
    } catch (const std::exception& e) {
      return Malformed(std::string(ScanFormatName(format)) + " file could not be parsed: " + e.what());
    }
    if (result < 0) {
      return Malformed(std::string(ScanFormatName(format)) +
                       " file could not be parsed (truncated, or its header does not match its data)");
    }
    // Our count, not PCL's width × height: a PLY camera element can change those while PCL reads.
    const uint64_t count = header.points;
    if (cloud_.point_step == 0 || cloud_.data.size() / cloud_.point_step < count) {
      return Truncated(std::string(ScanFormatName(format)) + " header declares " + std::to_string(count) +
                       " points but the data holds fewer");
    }
    info_.point_count = count;
    for (int axis = 0; axis < 3; ++axis) {
      const char* name = axis == 0 ? "x" : axis == 1 ? "y" : "z";
      xyz_[axis] = Find({name});
      if (!xyz_[axis]) return Malformed(std::string("no '") + name + "' field in the " + ScanFormatName(format) + " file");
    }
    packed_rgb_ = Find({"rgb", "rgba"});
    // Packed colors are read as 4 bytes; a 1- or 2-byte field called rgb is no packed color.
    if (packed_rgb_ && pcl::getFieldSize(packed_rgb_->datatype) != 4) packed_rgb_ = std::nullopt;
    if (!packed_rgb_) {
      red_ = Find({"red", "r", "diffuse_red"});
      green_ = Find({"green", "g", "diffuse_green"});
      blue_ = Find({"blue", "b", "diffuse_blue"});
      if (!(red_ && green_ && blue_)) red_ = green_ = blue_ = std::nullopt;
    }
    for (const auto* field : {&xyz_[0], &xyz_[1], &xyz_[2], &packed_rgb_, &red_, &green_, &blue_}) {
      if (*field && !FitsInPoint(**field)) {
        return Malformed(std::string(ScanFormatName(format)) + " field '" + (*field)->name + "' lies outside its point");
      }
    }
    info_.has_color = packed_rgb_.has_value() || red_.has_value();
    info_.stored_color_bits = 8;
    if (red_ && IsFloatType(red_->datatype)) color_scale_ = FloatColorScale();
    return Status::Ok();
  }

  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override {
    batch.clear();
    const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, info_.point_count - next_));
    batch.xyz.resize(n);
    if (info_.has_color) batch.rgb.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const unsigned char* point = cloud_.data.data() + (next_ + i) * cloud_.point_step;
      for (int axis = 0; axis < 3; ++axis) {
        const double v = LoadField(point + xyz_[axis]->offset, xyz_[axis]->datatype);
        if (!std::isfinite(v)) {
          return Malformed("point " + std::to_string(next_ + i) + " has a coordinate that is not finite");
        }
        batch.xyz[i][axis] = v;
      }
      if (info_.has_color) batch.rgb[i] = Color(point);
    }
    next_ += n;
    return n;
  }

  Status Rewind() override {
    next_ = 0;
    return Status::Ok();
  }

 private:
  std::optional<pcl::PCLPointField> Find(std::initializer_list<const char*> names) const {
    for (const char* name : names) {
      for (const auto& f : cloud_.fields) {
        if (f.name == name) return f;
      }
    }
    return std::nullopt;
  }

  bool FitsInPoint(const pcl::PCLPointField& f) const {
    const size_t size = pcl::getFieldSize(f.datatype);
    return size != 0 && uint64_t{f.offset} + size <= cloud_.point_step;
  }

  // Float channels are either in [0,1] or already in [0,255]; decide once for the whole cloud.
  double FloatColorScale() const {
    for (size_t i = 0; i < info_.point_count; ++i) {
      const unsigned char* point = cloud_.data.data() + i * cloud_.point_step;
      for (const auto* f : {&*red_, &*green_, &*blue_}) {
        if (LoadField(point + f->offset, f->datatype) > 1.0) return 1.0;
      }
    }
    return 255.0;
  }

  std::array<uint16_t, 3> Color(const unsigned char* point) {
    std::array<uint16_t, 3> c{};
    if (packed_rgb_) {
      uint32_t packed;
      std::memcpy(&packed, point + packed_rgb_->offset, 4);  // PCL packs 0x00RRGGBB in a float or uint32
      c = {static_cast<uint16_t>((packed >> 16) & 0xFF), static_cast<uint16_t>((packed >> 8) & 0xFF),
           static_cast<uint16_t>(packed & 0xFF)};
    } else {
      const pcl::PCLPointField* channels[3] = {&*red_, &*green_, &*blue_};
      for (int ch = 0; ch < 3; ++ch) {
        double v = LoadField(point + channels[ch]->offset, channels[ch]->datatype) * color_scale_;
        v = std::isfinite(v) ? std::clamp(std::round(v), 0.0, 255.0) : 0.0;
        c[ch] = static_cast<uint16_t>(v);
      }
    }
    for (uint16_t v : c) max_color_seen_ = std::max(max_color_seen_, v);
    return c;
  }

  pcl::PCLPointCloud2 cloud_;
  std::optional<pcl::PCLPointField> xyz_[3];
  std::optional<pcl::PCLPointField> packed_rgb_, red_, green_, blue_;
  double color_scale_ = 1.0;
  uint64_t next_ = 0;
};

}  // namespace

}  // namespace pointdag

// The module's one exported symbol (the rest is hidden: -fvisibility=hidden).
extern "C" __attribute__((visibility("default"))) void pointdag_open_pcl_scan(
    const char* path, pointdag::ScanFormat format, pointdag::StatusOr<std::unique_ptr<pointdag::ScanReader>>* out) {
  auto reader = std::make_unique<pointdag::PclScanReader>();
  const pointdag::Status loaded = reader->Load(path, format);
  *out = loaded.ok() ? pointdag::StatusOr<std::unique_ptr<pointdag::ScanReader>>(std::move(reader))
                     : pointdag::StatusOr<std::unique_ptr<pointdag::ScanReader>>(loaded);
}
