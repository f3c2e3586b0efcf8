// The yardstick: the same voxels coded by Google's Draco (libdraco, in-process).
//
// Positions go in as integer voxel coordinates and colors as 8-bit RGB, so Draco codes exactly
// what we code, losslessly. Draco has no single "best" setting, so every encoding method
// (sequential, kd-tree) and speed 0-10 is tried and the smallest result kept; the winner is decoded
// again to check it really is lossless.
#pragma once

#include <cstdint>
#include <string>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

struct DracoResult {
  size_t bytes = 0;
  double bits_per_point = 0;
  std::string method;  // "kd-tree" or "sequential"
  int speed = 0;
  // One encode with the kd-tree coder at speed 0 (draco_encoder -cl 10; its -qp 11 is moot for
  // integer voxel coordinates), the yardstick for our encode speed; Draco is single-threaded.
  double level10_seconds = 0;
  // Decoding the smallest encoding back to a point cloud, best of three (kExhaustive only; 0 for
  // kBestLevel), the yardstick for our decode rate (issue #14 goal 6).
  double decode_seconds = 0;
};

// kExhaustive: every method and speed, the smallest kept (the scorecard). kBestLevel: the kd-tree
// coder at speed 0, Draco's best compression level, which wins on every scan we measured; one
// encode instead of 22 (the daemon, per upload).
enum class DracoSearch { kExhaustive, kBestLevel };

StatusOr<DracoResult> DracoEncodeVoxels(const VoxelGrid& grid, DracoSearch search = DracoSearch::kExhaustive);

}  // namespace pointdag
