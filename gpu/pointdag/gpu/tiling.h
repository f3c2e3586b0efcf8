// How the tile-walking kernels (gpu/shaders/voxel_*.comp, dag_*.comp) cut their work, on the host
// side: one invocation walks one tile of kTile entries, workgroups of kGroupSize invocations, and
// a scan over all tiles runs in one invocation, so at most kMaxTiles tiles: lavapipe stops any loop
// once an invocation has run 65535 iterations in all (see gpu/shaders/block_common.glsl).
#pragma once

#include <cstdint>
#include <span>

namespace pointdag::gpu {

constexpr uint32_t kTile = 4096;  // as voxel_common.glsl and dag_common.glsl
constexpr uint32_t kGroupSize = 64;
constexpr uint32_t kMaxTiles = 60000;

// A kernel's name (its pipeline's key) and its embedded SPIR-V.
struct KernelSource {
  const char* name;
  std::span<const uint32_t> spirv;
};

}  // namespace pointdag::gpu
