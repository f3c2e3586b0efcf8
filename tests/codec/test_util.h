// Shared helpers for the codec tests: where the real scans are, scratch files, a LAS writer.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "pointdag/read/byte_io.h"
#include "pointdag/status.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
struct EncodedScan;  // pointdag/pipeline.h, which tests of the encoder include themselves
}  // namespace pointdag

namespace pointdag::testing {

// Autzen at 4 ft (36,931 voxels, lossless colors): the fixed case of the metadata and size
// regression tests.
StatusOr<EncodedScan> EncodeAutzenAt4Feet();

// ../shared/data beside the checkout (POINTDAG_DATA_DIR overrides).
inline std::filesystem::path DataDir() {
  if (const char* env = std::getenv("POINTDAG_DATA_DIR")) return env;
  return std::filesystem::path(POINTDAG_SOURCE_DIR) / ".." / "shared" / "data";
}

#define SKIP_WITHOUT_DATA()                                                                       \
  do {                                                                                           \
    if (!std::filesystem::exists(::pointdag::testing::DataDir() / "tiny_1.2-with-color_1065pts.las")) \
      GTEST_SKIP() << "real scans not found at " << ::pointdag::testing::DataDir()               \
                   << " (set POINTDAG_DATA_DIR); skipping";                                      \
  } while (0)

// A fresh scratch folder per test, removed afterwards.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("pointdag-test-" + std::string(info->test_suite_name()) + "-" + info->name() + "-" +
             std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() { std::filesystem::remove_all(path_); }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

struct CliRun {
  int exit_code;
  std::string out, err;
};

// Runs the real `pointdag` binary, after `env` (VAR=value ...) when given; stderr is captured through a file.
CliRun Cli(const std::string& args, const ScratchDir& dir, const std::string& env = "");

// Sorted unique Morton codes on a thin sheet, with the grid's lowest and highest corners (depth 21:
// every Morton bit): voxels as a surface scan gives them, for the color coders' tests.
inline std::vector<uint64_t> SheetMorton(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  constexpr uint32_t kMax = (1u << kMaxDepth) - 1;
  std::set<uint64_t> codes = {MortonEncode(0, 0, 0), MortonEncode(kMax, kMax, kMax), MortonEncode(kMax, 0, 1)};
  while (codes.size() < n) {
    const uint32_t x = rng() % 64, y = rng() % 64;
    codes.insert(MortonEncode(x, y, (x + y) / 8));
  }
  return {codes.begin(), codes.end()};
}

inline void WriteBytes(const std::filesystem::path& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

inline std::vector<uint8_t> ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct LasPoint {
  std::array<int32_t, 3> xyz;
  std::array<uint16_t, 3> rgb;
};

struct LasSpec {
  int minor = 4;                // 2 or 4
  int format = 7;               // 0..10
  int extra_bytes = 0;          // appended to each record
  double scale = 0.01;
  double offset = 1000.0;
  std::string wkt;              // written as VLR 2112 when not empty
  bool legacy_count = true;     // also fill the 32-bit count (1.4)
};

inline constexpr uint16_t kMinRecord[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
inline constexpr uint16_t kRgbAt[] = {0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30};

// Writes a LAS file by the book (ASPRS LAS 1.4 R15), for tests that need every format and fault.
inline std::vector<uint8_t> MakeLas(const LasSpec& spec, const std::vector<LasPoint>& points) {
  const uint16_t header_size = spec.minor >= 4 ? 375 : 227;
  const uint16_t record = static_cast<uint16_t>(kMinRecord[spec.format] + spec.extra_bytes);
  std::vector<uint8_t> vlr;
  if (!spec.wkt.empty()) {
    AppendLE<uint16_t>(vlr, 0);
    const char user[16] = "LASF_Projection";
    vlr.insert(vlr.end(), user, user + 16);
    AppendLE<uint16_t>(vlr, 2112);
    AppendLE<uint16_t>(vlr, static_cast<uint16_t>(spec.wkt.size() + 1));
    vlr.resize(vlr.size() + 32, 0);
    vlr.insert(vlr.end(), spec.wkt.begin(), spec.wkt.end());
    vlr.push_back(0);
  }
  std::vector<uint8_t> h(header_size, 0);
  std::memcpy(h.data(), "LASF", 4);
  h[24] = 1;
  h[25] = static_cast<uint8_t>(spec.minor);
  auto put = [&](size_t at, auto v) { std::memcpy(h.data() + at, &v, sizeof(v)); };
  put(94, header_size);
  put(96, static_cast<uint32_t>(header_size + vlr.size()));
  put(100, static_cast<uint32_t>(spec.wkt.empty() ? 0 : 1));
  h[104] = static_cast<uint8_t>(spec.format);
  put(105, record);
  if (spec.legacy_count || spec.minor < 4) put(107, static_cast<uint32_t>(points.size()));
  for (int a = 0; a < 3; ++a) {
    put(131 + 8 * a, spec.scale);
    put(155 + 8 * a, spec.offset);
  }
  if (spec.minor >= 4) put(247, static_cast<uint64_t>(points.size()));
  std::vector<uint8_t> out = h;
  out.insert(out.end(), vlr.begin(), vlr.end());
  for (const auto& p : points) {
    std::vector<uint8_t> rec(record, 0);
    std::memcpy(rec.data(), p.xyz.data(), 12);
    if (kRgbAt[spec.format]) std::memcpy(rec.data() + kRgbAt[spec.format], p.rgb.data(), 6);
    for (int i = 0; i < spec.extra_bytes; ++i) rec[kMinRecord[spec.format] + i] = 0xEE;  // must be skipped
    out.insert(out.end(), rec.begin(), rec.end());
  }
  return out;
}

inline std::vector<LasPoint> RandomLasPoints(size_t n, uint32_t seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int32_t> coord(-5000, 5000);
  std::uniform_int_distribution<int> color(0, 65535);
  std::vector<LasPoint> points(n);
  for (auto& p : points) {
    p.xyz = {coord(rng), coord(rng), coord(rng)};
    p.rgb = {static_cast<uint16_t>(color(rng)), static_cast<uint16_t>(color(rng)), static_cast<uint16_t>(color(rng))};
  }
  return points;
}

// Sorted unique random Morton codes on a depth-`depth` grid, clustered on a few surfaces so that
// the DAG has shared subtrees as well as unique ones.
std::vector<uint64_t> SurfaceVoxels(int depth, size_t approx, uint32_t seed);

// A scan in ../shared/data and the voxel size a test uses it at.
struct ScanAtVoxel {
  const char* file;
  double voxel;
};

// Every scan in ../shared/data, at a voxel size fine enough to keep most of its points.
inline constexpr ScanAtVoxel kEveryScan[] = {
    {"tiny_1.2-with-color_1065pts.las", 4.0},
    {"autzen_trim_pdrf3_rgb.las", 4.0},
    {"autzen_trim_las14_pdrf7_rgb.las", 2.0},
    {"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", 0.25},
    {"lion_takanawa_pdrf7_rgb.las", 0.01},
    {"lone_star_tls_noRGB.las", 0.05},
    {"pcx_guanyin_cc-by-4.0_rgb.ply", 0.002},
    {"pcl_milk_cartoon_clorox_kinect_rgb.ply", 0.004},
};

// gtest's name generator for parameters that are, or have a `file` member naming, a scan file:
// "autzen_trim_pdrf3_rgb.las" -> "autzen_trim_pdrf3_rgb_las".
struct ScanFileName {
  template <typename Param>
  std::string operator()(const ::testing::TestParamInfo<Param>& param_info) const {
    std::string name;
    if constexpr (std::is_convertible_v<Param, const char*>) {
      name = param_info.param;
    } else {
      name = param_info.param.file;
    }
    for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    return name;
  }
};

// The same with the voxel size, for lists that hold a scan at several: "..._las_at_0_25".
struct ScanFileAndVoxelName {
  std::string operator()(const ::testing::TestParamInfo<ScanAtVoxel>& param_info) const {
    std::ostringstream voxel;
    voxel << param_info.param.voxel;
    std::string name = std::string(param_info.param.file) + "_at_" + voxel.str();
    for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    return name;
  }
};

}  // namespace pointdag::testing
