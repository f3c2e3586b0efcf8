// Calibrations kept across processes: under POINTDAG_DEVICE=auto each stage's CPU-vs-Vulkan timing is
// measured once per machine, not once per process (a CLI run on lavapipe spent ~1.5 s on it).
//
// The file is $XDG_CACHE_HOME/pointdag/calibration.tsv, else ~/.cache/pointdag/calibration.tsv; no
// cache without either variable. One line per stage: key, stage, CPU seconds, Vulkan seconds, tab
// separated. The key names the device (VulkanContext::device_key) and this build of pointdag (the
// executable's size and modification time), so a new driver, device or build measures again. Lines
// that do not parse, or have another key, are ignored; a store rewrites the file (through a
// temporary file and a rename, so that readers never see half of it). Caching is best effort:
// failing to read or write only means measuring again.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "pointdag/gpu/stage_device.h"

namespace pointdag::gpu {

// The cache file's path, or empty when neither XDG_CACHE_HOME nor HOME is set.
std::filesystem::path CalibrationCachePath();

// `device_key` joined with this build's identity.
std::string CalibrationKey(const std::string& device_key);

std::optional<StageTiming> LoadCalibration(const std::filesystem::path& file, const std::string& key, Stage stage);

// Keeps the file's other valid lines with this key, replaces this stage's.
void StoreCalibration(const std::filesystem::path& file, const std::string& key, Stage stage, const StageTiming& timing);

}  // namespace pointdag::gpu
