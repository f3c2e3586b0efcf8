// Which path each heavy stage takes in this process: its CPU implementation or its Vulkan kernels.
//
// POINTDAG_DEVICE picks: `cpu` never opens Vulkan; `vulkan` puts every stage that has kernels on the
// best device (a discrete GPU, then an integrated one, then a virtual one, then Mesa lavapipe on the
// CPU) and is an error with a clear message when no device opens; `auto` (the default) opens the
// best device and then, once per stage, times both paths on a small synthetic input and keeps the
// faster (the timing is cached per machine: calibration_cache.h). Under `auto` without a usable device the process says so once (stderr) and uses the CPU.
// Both paths give identical results (tests/gpu/gpu_test.cc), so the choice only changes speed.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "pointdag/gpu/vulkan_context.h"
#include "pointdag/status.h"

namespace pointdag::gpu {

enum class DeviceChoice { kAuto, kVulkan, kCpu };

StatusOr<DeviceChoice> ParseDeviceChoice(std::string_view text);  // "auto" | "vulkan" | "cpu"

// Stages with Vulkan kernels.
enum class Stage { kVoxelize, kDagHashes, kColorBlocks };
const char* StageName(Stage stage);

// The process's device from POINTDAG_DEVICE, opened once (thread-safe). Null under `cpu`, or under
// `auto` when none opens. An error when POINTDAG_DEVICE is unknown, or is `vulkan` and none opens.
StatusOr<VulkanContext*> ProcessDevice();

// Seconds each path took on a stage's calibration input (Vulkan after a warm-up run, which builds
// the pipelines once per process).
struct StageTiming {
  double cpu_seconds = 0, vulkan_seconds = 0;
};
// Runs the stage both ways. It may use tbb inside, isolated (tbb::this_task_arena::isolate), since
// DeviceFor holds a lock while it runs.
using Calibration = std::function<StatusOr<StageTiming>(VulkanContext&)>;

// The device `stage` runs on, null for the CPU path. Under `auto`, `calibrate` decides, once per
// machine, device and build: its timing is cached (calibration_cache.h) and read back by later
// processes; a calibration that fails leaves the stage on the CPU (and is not cached). Under `auto` an input smaller than
// the calibration's (`small_input`) stays on the CPU too: the measurement says nothing about it, and
// a dispatch's fixed cost dominates it (thousands of one-voxel tiles took ~100 ms each on lavapipe).
StatusOr<VulkanContext*> DeviceFor(Stage stage, const Calibration& calibrate, bool small_input = false);

struct StageChoice {
  Stage stage;
  bool vulkan = false;
  std::string device;  // "cpu" or the Vulkan device's name
  std::string reason;  // why: the setting, the missing device, or the measured times
  StageTiming timing;  // the calibration's, when it ran
};
std::vector<StageChoice> StageChoices();  // the stages decided so far, in Stage order

// One line for logs: "color_blocks: cpu (measured: cpu 10.2 ms, vulkan 88.1 ms on llvmpipe ...)"
// ("cached: ..." where an earlier process measured it).
std::string DescribeDevices();

// Tests and benchmarks: forget the process's choices so that the next call reads POINTDAG_DEVICE
// again (a device once opened stays open). Vulkan does not survive fork(): a process that forks
// workers (pointdag bench) must leave opening it to them.
void ResetProcessDevice();

}  // namespace pointdag::gpu
