#include "pointdag/gpu/stage_device.h"

#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>

#include "pointdag/gpu/calibration_cache.h"

namespace pointdag::gpu {
namespace {

struct ProcessState {
  std::mutex mutex;
  bool chosen = false;
  DeviceChoice choice = DeviceChoice::kAuto;
  Status error;                    // POINTDAG_DEVICE unknown, or vulkan required and not there
  bool opened = false;             // Vulkan was tried (once per process)
  std::unique_ptr<VulkanContext> context;
  Status open_error;
  std::map<Stage, StageChoice> stages;
};

ProcessState& State() {
  // Never destroyed: a driver torn down by static destructors after its own can crash at exit.
  static ProcessState* state = new ProcessState;
  return *state;
}

// ProcessDevice with the state's lock held.
StatusOr<VulkanContext*> ChooseLocked(ProcessState& s) {
  if (!s.chosen) {
    s.chosen = true;
    s.stages.clear();
    const char* env = std::getenv("POINTDAG_DEVICE");
    auto choice = ParseDeviceChoice(env ? env : "auto");
    s.error = choice.status();
    if (choice.ok()) s.choice = *choice;
    if (s.error.ok() && s.choice != DeviceChoice::kCpu && !s.opened) {
      s.opened = true;
      auto context = VulkanContext::Create();
      if (context.ok()) {
        s.context = std::move(*context);
      } else {
        s.open_error = context.status();
        if (s.choice == DeviceChoice::kAuto) {
          std::fprintf(stderr, "pointdag: no usable Vulkan device (%s); running on the CPU\n", s.open_error.message().c_str());
        }
      }
    }
    if (s.error.ok() && s.choice == DeviceChoice::kVulkan && !s.context) {
      s.error = Status(StatusCode::kUnsupported, "POINTDAG_DEVICE=vulkan but no Vulkan device could be used: " + s.open_error.message());
    }
  }
  if (!s.error.ok()) return s.error;
  return s.choice == DeviceChoice::kCpu ? nullptr : s.context.get();
}

std::string Milliseconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f ms", seconds * 1e3);
  return text;
}

}  // namespace

StatusOr<DeviceChoice> ParseDeviceChoice(std::string_view text) {
  if (text == "auto" || text.empty()) return DeviceChoice::kAuto;
  if (text == "vulkan") return DeviceChoice::kVulkan;
  if (text == "cpu") return DeviceChoice::kCpu;
  return InvalidArgument("POINTDAG_DEVICE must be auto, vulkan or cpu, not '" + std::string(text) + "'");
}

const char* StageName(Stage stage) {
  switch (stage) {
    case Stage::kVoxelize: return "voxelize";
    case Stage::kDagHashes: return "dag_hashes";
    case Stage::kColorBlocks: return "color_blocks";
  }
  return "?";
}

StatusOr<VulkanContext*> ProcessDevice() {
  ProcessState& s = State();
  std::lock_guard lock(s.mutex);
  return ChooseLocked(s);
}

StatusOr<VulkanContext*> DeviceFor(Stage stage, const Calibration& calibrate, bool small_input) {
  ProcessState& s = State();
  std::lock_guard lock(s.mutex);
  ASSIGN_OR_RETURN(VulkanContext* const context, ChooseLocked(s));
  if (small_input && s.choice == DeviceChoice::kAuto) return nullptr;
  if (auto it = s.stages.find(stage); it != s.stages.end()) return it->second.vulkan ? context : nullptr;
  StageChoice made{stage, false, "cpu", "", {}};
  if (s.choice == DeviceChoice::kCpu) {
    made.reason = "POINTDAG_DEVICE=cpu";
  } else if (!context) {
    made.reason = "no usable Vulkan device: " + s.open_error.message();
  } else if (s.choice == DeviceChoice::kVulkan) {
    made = {stage, true, context->device_name(), "POINTDAG_DEVICE=vulkan", {}};
  } else {
    const std::filesystem::path cache = CalibrationCachePath();
    const std::string key = CalibrationKey(context->device_key());
    std::optional<StageTiming> cached = LoadCalibration(cache, key, stage);
    StatusOr<StageTiming> timing = cached ? StatusOr<StageTiming>(*cached) : calibrate(*context);
    if (!timing.ok()) {
      made.reason = "the Vulkan path failed its calibration run: " + timing.status().message();
    } else {
      if (!cached) StoreCalibration(cache, key, stage, *timing);
      made.timing = *timing;
      made.vulkan = timing->vulkan_seconds < timing->cpu_seconds;
      if (made.vulkan) made.device = context->device_name();
      made.reason = std::string(cached ? "cached: " : "measured: ") + "cpu " + Milliseconds(timing->cpu_seconds) + ", vulkan " +
                    Milliseconds(timing->vulkan_seconds) + " on " + context->device_name();
    }
  }
  s.stages[stage] = made;
  return made.vulkan ? context : nullptr;
}

std::vector<StageChoice> StageChoices() {
  ProcessState& s = State();
  std::lock_guard lock(s.mutex);
  std::vector<StageChoice> out;
  for (const auto& [stage, choice] : s.stages) out.push_back(choice);
  return out;
}

std::string DescribeDevices() {
  std::string out;
  for (const StageChoice& c : StageChoices()) {
    out += std::string(out.empty() ? "" : "; ") + StageName(c.stage) + ": " + (c.vulkan ? "vulkan (" + c.device + ")" : "cpu") + " (" +
           c.reason + ")";
  }
  return out.empty() ? "no stage decided yet" : out;
}

void ResetProcessDevice() {
  ProcessState& s = State();
  std::lock_guard lock(s.mutex);
  s.chosen = false;
}

}  // namespace pointdag::gpu
