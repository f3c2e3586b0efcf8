#include <gtest/gtest.h>
#include <xxhash.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "pointdag/color/block_codec.h"
#include "pointdag/gpu/calibration_cache.h"
#include "pointdag/gpu/color_blocks.h"
#include "pointdag/gpu/dag_hashes.h"
#include "pointdag/gpu/stage_device.h"
#include "pointdag/gpu/voxel_reduce.h"
#include "pointdag/gpu/vulkan_context.h"
#include "pointdag/pipeline.h"
#include "pointdag/voxelize/morton.h"
#include "../codec/test_util.h"

namespace pointdag::gpu {
namespace {

// Sets POINTDAG_DEVICE for one test and makes the process choose again, with an empty calibration
// cache of its own (XDG_CACHE_HOME), so that no earlier run's timings decide.
class DeviceEnv {
 public:
  explicit DeviceEnv(const char* value) {
    static int serial = 0;
    cache_home_ = std::filesystem::temp_directory_path() /
                  ("pointdag_gpu_test_" + std::to_string(getpid()) + "_" + std::to_string(serial++));
    setenv("XDG_CACHE_HOME", cache_home_.c_str(), 1);
    setenv("POINTDAG_DEVICE", value, 1);
    ResetProcessDevice();
  }
  ~DeviceEnv() {
    unsetenv("POINTDAG_DEVICE");
    unsetenv("XDG_CACHE_HOME");
    ResetProcessDevice();
    std::filesystem::remove_all(cache_home_);
  }
  // Another process on the same machine: same cache, choices made again.
  static void NextProcess() { ResetProcessDevice(); }

 private:
  std::filesystem::path cache_home_;
};

TEST(DeviceChoice, ParsesTheThreeWordsAndRefusesOthers) {
  EXPECT_EQ(*ParseDeviceChoice("auto"), DeviceChoice::kAuto);
  EXPECT_EQ(*ParseDeviceChoice("vulkan"), DeviceChoice::kVulkan);
  EXPECT_EQ(*ParseDeviceChoice("cpu"), DeviceChoice::kCpu);
  const auto bad = ParseDeviceChoice("gpu");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("auto, vulkan or cpu"), std::string::npos);
}

// A calibration that must not run, and ones that report fixed times.
StatusOr<StageTiming> NotCalled(VulkanContext&) {
  ADD_FAILURE() << "calibration ran";
  return StageTiming{};
}
Calibration Measured(double cpu_seconds, double vulkan_seconds) {
  return [=](VulkanContext&) -> StatusOr<StageTiming> { return StageTiming{cpu_seconds, vulkan_seconds}; };
}

TEST(DeviceChoice, CpuNeverOpensVulkanAndUnknownValuesAreErrors) {
  {
    DeviceEnv env("cpu");
    EXPECT_EQ(*ProcessDevice(), nullptr);
    EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, NotCalled), nullptr);
    EXPECT_EQ(DescribeDevices(), "color_blocks: cpu (POINTDAG_DEVICE=cpu)");
  }
  DeviceEnv env("fastest");
  EXPECT_FALSE(ProcessDevice().ok());
  EXPECT_EQ(DeviceFor(Stage::kColorBlocks, NotCalled).status().code(), StatusCode::kInvalidArgument);
}

// CI installs mesa-vulkan-drivers, so lavapipe is there at least: `vulkan` must open a device and
// put the stages on it; `auto` keeps the faster path by the calibration's times, once per process.
TEST(DeviceChoice, VulkanOpensADeviceAndAutoKeepsTheMeasuredFasterPath) {
  VulkanContext* vulkan = nullptr;
  {
    DeviceEnv env("vulkan");
    auto device = ProcessDevice();
    ASSERT_TRUE(device.ok()) << device.status().message();
    ASSERT_NE(*device, nullptr);
    vulkan = *device;
    EXPECT_FALSE(vulkan->device_name().empty());
    EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, NotCalled), vulkan);
    EXPECT_EQ(DescribeDevices(), "color_blocks: vulkan (" + vulkan->device_name() + ") (POINTDAG_DEVICE=vulkan)");
  }
  {
    DeviceEnv env("auto");
    EXPECT_EQ(*ProcessDevice(), vulkan);  // opened once per process
    EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, Measured(0.010, 0.020)), nullptr);
    EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, Measured(0.020, 0.010)), nullptr) << "decided once";
    EXPECT_EQ(DescribeDevices(), "color_blocks: cpu (measured: cpu 10.0 ms, vulkan 20.0 ms on " + vulkan->device_name() + ")");
  }
  {
    DeviceEnv env("auto");
    EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, Measured(0.020, 0.010)), vulkan);
  }
  DeviceEnv env("auto");
  const auto failing = [](VulkanContext&) -> StatusOr<StageTiming> { return Internal("lost the device"); };
  EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, failing), nullptr);
  ASSERT_EQ(StageChoices().size(), 1u);
  EXPECT_NE(StageChoices()[0].reason.find("lost the device"), std::string::npos);
}

// The codec's own calibration runs both paths for real and records what it measured.
TEST(DeviceChoice, ColorBlocksCalibrationMeasuresBothPaths) {
  DeviceEnv env("auto");
  auto device = ColorBlocksDevice();
  ASSERT_TRUE(device.ok()) << device.status().message();
  const auto choices = StageChoices();
  ASSERT_EQ(choices.size(), 1u);
  EXPECT_EQ(choices[0].vulkan, *device != nullptr);
  EXPECT_EQ(choices[0].reason.rfind("measured: cpu ", 0), 0u) << choices[0].reason;
}

// A later process reads the first one's calibration instead of measuring again.
TEST(CalibrationCache, ASecondProcessReadsTheFirstOnesTiming) {
  DeviceEnv env("auto");
  auto device = ProcessDevice();
  ASSERT_TRUE(device.ok() && *device) << "needs a Vulkan device (lavapipe at least)";
  EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, Measured(0.020, 0.010)), *device);
  DeviceEnv::NextProcess();
  EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, NotCalled), *device);
  EXPECT_EQ(DescribeDevices(), "color_blocks: vulkan (" + (*device)->device_name() + ") (cached: cpu 20.0 ms, vulkan 10.0 ms on " +
                                   (*device)->device_name() + ")");
  // Each stage has its own line; another device or build has its own key.
  EXPECT_EQ(*DeviceFor(Stage::kVoxelize, Measured(0.010, 0.020)), nullptr);
  const std::string key = CalibrationKey((*device)->device_key());
  EXPECT_EQ(LoadCalibration(CalibrationCachePath(), key, Stage::kColorBlocks)->vulkan_seconds, 0.010);
  EXPECT_EQ(LoadCalibration(CalibrationCachePath(), key, Stage::kVoxelize)->vulkan_seconds, 0.020);
  EXPECT_FALSE(LoadCalibration(CalibrationCachePath(), "another device", Stage::kColorBlocks));
}

// A corrupt file is ignored (the stage is measured again) and rewritten with the new timing.
TEST(CalibrationCache, ACorruptFileIsMeasuredAgainAndRewritten) {
  DeviceEnv env("auto");
  auto device = ProcessDevice();
  ASSERT_TRUE(device.ok() && *device) << "needs a Vulkan device (lavapipe at least)";
  const std::filesystem::path file = CalibrationCachePath();
  const std::string key = CalibrationKey((*device)->device_key());
  std::filesystem::create_directories(file.parent_path());
  std::ofstream(file) << "\x01garbage\n" << key << "\tcolor_blocks\tnan\t0.5\n" << key << "\tcolor_blocks\t0.1\n";
  EXPECT_FALSE(LoadCalibration(file, key, Stage::kColorBlocks));
  EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, Measured(0.020, 0.010)), *device);
  EXPECT_EQ(StageChoices()[0].reason.rfind("measured: ", 0), 0u);
  const auto stored = LoadCalibration(file, key, Stage::kColorBlocks);
  ASSERT_TRUE(stored);
  EXPECT_EQ(stored->cpu_seconds, 0.020);
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("garbage"), std::string::npos);
}

// A failed calibration is not cached: the next process tries again.
TEST(CalibrationCache, AFailedCalibrationIsNotCached) {
  DeviceEnv env("auto");
  auto device = ProcessDevice();
  ASSERT_TRUE(device.ok() && *device) << "needs a Vulkan device (lavapipe at least)";
  const auto failing = [](VulkanContext&) -> StatusOr<StageTiming> { return Internal("lost the device"); };
  EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, failing), nullptr);
  DeviceEnv::NextProcess();
  EXPECT_EQ(*DeviceFor(Stage::kColorBlocks, Measured(0.020, 0.010)), *device);
}

TEST(ColorBlocksKernel, EqualColorsGiveOneZeroBitBlockPerMacroBlock) {
  DeviceEnv env("vulkan");
  auto device = ProcessDevice();
  ASSERT_TRUE(device.ok()) << device.status().message();
  std::vector<uint8_t> rgb;
  for (int i = 0; i < 16384 * 2 + 5; ++i) rgb.insert(rgb.end(), {1, 2, 3});
  auto blocks = EncodeColorBlocks(**device, rgb, false, 3072 * 10);
  ASSERT_TRUE(blocks.ok()) << blocks.status().message();
  ASSERT_EQ(blocks->size(), 3u);
  const uint32_t starts[] = {0, 16384, 32768}, lengths[] = {16384, 16384, 5};
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ((*blocks)[k].start, starts[k]);
    EXPECT_EQ((*blocks)[k].length, lengths[k]);
    EXPECT_EQ((*blocks)[k].bits, 0);
    EXPECT_EQ((*blocks)[k].a[0], 1);
    EXPECT_EQ((*blocks)[k].a[2], 3);
  }
}

// Blocks from one path, chosen by POINTDAG_DEVICE.
std::vector<ColorBlock> BlocksOn(const char* device, std::span<const Rgb8> colors, BlockLayout layout, double max_mse) {
  DeviceEnv env(device);
  auto blocks = EncodeBlocks(colors, layout, max_mse);
  EXPECT_TRUE(blocks.ok()) << blocks.status().message();
  return blocks.ok() ? *blocks : std::vector<ColorBlock>{};
}

std::string Describe(const ColorBlock& b) {
  return std::to_string(b.start) + "+" + std::to_string(b.length) + " " + std::to_string(b.bits) + "b (" +
         std::to_string(b.ends.a.r) + "," + std::to_string(b.ends.a.g) + "," + std::to_string(b.ends.a.b) + ")-(" +
         std::to_string(b.ends.b.r) + "," + std::to_string(b.ends.b.g) + "," + std::to_string(b.ends.b.b) + ")";
}

void ExpectSameBlocks(std::span<const Rgb8> colors, BlockLayout layout, double max_mse) {
  const auto cpu = BlocksOn("cpu", colors, layout, max_mse);
  const auto vulkan = BlocksOn("vulkan", colors, layout, max_mse);
  for (size_t k = 0; k < std::min(cpu.size(), vulkan.size()); ++k) ASSERT_EQ(Describe(cpu[k]), Describe(vulkan[k])) << "block " << k;
  ASSERT_EQ(cpu.size(), vulkan.size());
}

TEST(ColorBlocksKernel, SameBlocksAsTheCpuOnRandomColors) {
  std::mt19937 rng(7);
  for (uint32_t n : {2u, 5u, 17u, 64u, 200u, 1000u, 4000u, 16383u}) {
    std::vector<Rgb8> colors(n);
    for (Rgb8& c : colors) c = {uint8_t(rng()), uint8_t(rng()), uint8_t(rng())};
    for (const double max_mse : {0.0, 50.0, 400.0, 3000.0}) {
      SCOPED_TRACE("n " + std::to_string(n) + " max_mse " + std::to_string(max_mse));
      ExpectSameBlocks(colors, BlockLayout::kFixedRate, max_mse);
      ExpectSameBlocks(colors, BlockLayout::kVariableRate, max_mse);
      if (HasFatalFailure()) return;
    }
  }
}

TEST(VoxelKernels, MortonCodesAreMortonEncode) {
  DeviceEnv env("vulkan");
  auto device = ProcessDevice();
  ASSERT_TRUE(device.ok()) << device.status().message();
  std::mt19937 rng(3);
  std::vector<std::array<uint32_t, 3>> cells = {{0, 0, 0}, {0x1FFFFF, 0x1FFFFF, 0x1FFFFF}, {1, 0, 0}, {0, 0, 1}};
  const auto coordinate = [&] { return static_cast<uint32_t>(rng() & 0x1FFFFF); };
  for (int i = 0; i < 100000; ++i) cells.push_back({coordinate(), coordinate(), coordinate()});
  auto codes = MortonCodes(**device, cells);
  ASSERT_TRUE(codes.ok()) << codes.status().message();
  ASSERT_EQ(codes->size(), cells.size());
  for (size_t i = 0; i < cells.size(); ++i) ASSERT_EQ((*codes)[i], MortonEncode(cells[i][0], cells[i][1], cells[i][2])) << "cell " << i;
}

// Radix sort, unique and mean against a plain map: duplicates within and across tiles (one voxel
// holds 70000 points over 18 tiles, its 16-bit sums past 2^32), codes using all 63 bits, 8- and
// 16-bit colors (divisor 1 and 257).
TEST(VoxelKernels, OneVoxelPerCodeWithTheMeanRoundedHalfUp) {
  DeviceEnv env("vulkan");
  auto device = ProcessDevice();
  ASSERT_TRUE(device.ok()) << device.status().message();
  std::mt19937_64 rng(11);
  std::vector<uint64_t> keys;
  std::vector<std::array<uint16_t, 3>> rgb;
  for (int i = 0; i < 90000; ++i) {
    keys.push_back(i < 70000 ? 12345 : (rng() >> 1) % (i < 80000 ? 500 : uint64_t{1} << 63));
    rgb.push_back({uint16_t(i < 70000 ? 65535 : rng()), uint16_t(i < 70000 ? 65000 + i % 500 : rng()), uint16_t(rng())});
  }
  for (const uint32_t divisor : {1u, 257u}) {
    std::map<uint64_t, std::array<uint64_t, 4>> expected;  // sums, points
    for (size_t i = 0; i < keys.size(); ++i) {
      auto& e = expected[keys[i]];
      for (int c = 0; c < 3; ++c) e[c] += divisor == 1 ? rgb[i][c] & 255 : rgb[i][c];
      ++e[3];
    }
    auto input = rgb;
    if (divisor == 1) {
      for (auto& c : input) c = {uint16_t(c[0] & 255), uint16_t(c[1] & 255), uint16_t(c[2] & 255)};
    }
    auto voxels = ReduceVoxels(**device, keys, input, 63, divisor);
    ASSERT_TRUE(voxels.ok()) << voxels.status().message();
    ASSERT_EQ(voxels->morton.size(), expected.size());
    size_t v = 0;
    for (const auto& [key, e] : expected) {
      ASSERT_EQ(voxels->morton[v], key) << "voxel " << v;
      for (int c = 0; c < 3; ++c) {
        const uint64_t d = e[3] * divisor;
        ASSERT_EQ(voxels->colors[v][c], std::min<uint64_t>((2 * e[c] + d) / (2 * d), 255)) << "voxel " << v << " channel " << c;
      }
      ++v;
    }
  }
}

// The hashes of HashDagLevels against XXH3 computed here, as the CPU builder hashes cells: bricks
// from their mask, nodes from their mask and their children's hashes.
void ExpectBuilderHashes(const std::vector<uint64_t>& morton, int depth) {
  auto device = ProcessDevice();
  ASSERT_TRUE(device.ok() && *device) << "no Vulkan device";
  auto gpu = HashDagLevels(**device, morton, depth);
  ASSERT_TRUE(gpu.ok()) << gpu.status().message();
  std::vector<uint64_t> keys = morton, hashes;
  for (int height = 2; height <= depth; ++height) {
    const int shift = height == 2 ? 6 : 3;
    std::vector<uint64_t> next_keys, next_hashes;
    for (size_t i = 0; i < keys.size();) {
      std::vector<uint64_t> words = {0};
      size_t j = i;
      for (; j < keys.size() && keys[j] >> shift == keys[i] >> shift; ++j) {
        words[0] |= uint64_t{1} << (keys[j] & ((uint64_t{1} << shift) - 1));
        if (height > 2) words.push_back(hashes[j]);
      }
      next_keys.push_back(keys[i] >> shift);
      next_hashes.push_back(XXH3_64bits(words.data(), 8 * words.size()));
      i = j;
    }
    ASSERT_EQ(gpu->hashes[height].size(), next_hashes.size()) << "height " << height;
    for (size_t k = 0; k < next_hashes.size(); ++k) ASSERT_EQ(gpu->hashes[height][k], next_hashes[k]) << "height " << height << " cell " << k;
    keys.swap(next_keys);
    hashes.swap(next_hashes);
  }
  EXPECT_EQ(gpu->hashes[depth].size(), 1u);
}

// Every input length (8 to 72 bytes), several tiles per level, and 4096 full bricks in a row (the
// kernels must keep each invocation under lavapipe's loop limit however dense the voxels).
TEST(DagKernels, LevelHashesAreTheBuildersXxh3) {
  DeviceEnv env("vulkan");
  std::mt19937_64 rng(5);
  std::vector<uint64_t> morton;
  for (int i = 0; i < 400000; ++i) morton.push_back(rng() % (uint64_t{1} << 27));  // dense low corner
  for (uint64_t c = 0; c < (1 << 18); ++c) morton.push_back((uint64_t{3} << 30) | c);  // full subtrees: 8 children
  std::sort(morton.begin(), morton.end());
  morton.erase(std::unique(morton.begin(), morton.end()), morton.end());
  ExpectBuilderHashes(morton, 12);
}

// The rule of issue #5: the Vulkan path writes the CPU path's .pdag bytes, on every scan, for
// both block codecs, for mipmapped colors (which code DAG-order colors) and when voxelizing in
// spilled chunks.
class SameFileTest : public ::testing::TestWithParam<testing::ScanAtVoxel> {};

TEST_P(SameFileTest, VulkanWritesTheCpuPathsBytes) {
  SKIP_WITHOUT_DATA();
  EncodeOptions options;
  options.voxel_size = GetParam().voxel;
  const auto encode = [&](const char* device) {
    DeviceEnv env(device);
    auto scan = EncodeScan(testing::DataDir() / GetParam().file, options);
    EXPECT_TRUE(scan.ok()) << device << ": " << scan.status().ToString();
    return scan.ok() ? SerializePdag(scan->file) : std::vector<uint8_t>{};
  };
  for (const ColorCodec codec : {ColorCodec::kVariableRate, ColorCodec::kFixedRate}) {
    for (const bool mipmap : {false, true}) {
      if (mipmap && codec == ColorCodec::kFixedRate) continue;
      SCOPED_TRACE(std::string(ColorCodecName(codec)) + (mipmap ? " mipmap" : ""));
      options.colors = {codec, std::nullopt};
      options.mipmap = mipmap;
      const auto cpu = encode("cpu");
      ASSERT_FALSE(cpu.empty());
      EXPECT_TRUE(cpu == encode("vulkan"));
      if (codec == ColorCodec::kVariableRate && !mipmap) {
        // Spilled to chunks, each reduced and built on its own: still the same file.
        options.max_points_in_memory = 60000;
        EXPECT_TRUE(cpu == encode("vulkan")) << "chunked";
        options.max_points_in_memory = uint64_t{1} << 25;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(SharedData, SameFileTest, ::testing::ValuesIn(testing::kEveryScan), testing::ScanFileName());

}  // namespace
}  // namespace pointdag::gpu
