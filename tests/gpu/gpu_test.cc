#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "pointdag/color/block_codec.h"
#include "pointdag/gpu/color_blocks.h"
#include "pointdag/gpu/vulkan_context.h"

namespace pointdag::gpu {
namespace {

// Sets POINTDAG_DEVICE for one test and makes the process choose again.
class DeviceEnv {
 public:
  explicit DeviceEnv(const char* value) {
    setenv("POINTDAG_DEVICE", value, 1);
    ResetProcessDeviceForTesting();
  }
  ~DeviceEnv() {
    unsetenv("POINTDAG_DEVICE");
    ResetProcessDeviceForTesting();
  }
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

TEST(DeviceChoice, CpuNeverOpensVulkanAndUnknownValuesAreErrors) {
  {
    DeviceEnv env("cpu");
    EXPECT_EQ(*ProcessDevice(), nullptr);
    EXPECT_EQ(*DeviceFor(Stage::kColorBlocks), nullptr);
    EXPECT_EQ(DescribeDevices(), "color_blocks: cpu");
  }
  DeviceEnv env("fastest");
  EXPECT_FALSE(ProcessDevice().ok());
}

// CI installs mesa-vulkan-drivers, so lavapipe is there at least: `vulkan` must open a device, and
// `auto` keeps a CPU implementation off the stages (measured slower there).
TEST(DeviceChoice, VulkanOpensADeviceAndAutoKeepsSoftwareOffTheStages) {
  VulkanContext* vulkan = nullptr;
  {
    DeviceEnv env("vulkan");
    auto device = ProcessDevice();
    ASSERT_TRUE(device.ok()) << device.status().message();
    ASSERT_NE(*device, nullptr);
    vulkan = *device;
    EXPECT_FALSE(vulkan->device_name().empty());
    EXPECT_EQ(*DeviceFor(Stage::kColorBlocks), vulkan);
  }
  DeviceEnv env("auto");
  EXPECT_EQ(*ProcessDevice(), vulkan);  // opened once per process
  EXPECT_EQ(*DeviceFor(Stage::kColorBlocks), vulkan->software() ? nullptr : vulkan);
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

}  // namespace
}  // namespace pointdag::gpu
