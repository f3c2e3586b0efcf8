// Shared by the DAG hashing kernels (dag_*.comp): one level of the octree at a time, from the
// sorted keys of the level below (Morton codes of voxels for the bricks), the cells of this level
// and each cell's subtree hash, XXH3-64 (seed 0) exactly as codec/pointdag/dag/dag_builder.cc
// computes it on the CPU: of a brick's 64-bit mask; of a node's mask and its children's hashes.
// Tiles of kTile entries per invocation, as in voxel_common.glsl (lavapipe's loop limit).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(push_constant) uniform Params {
  uint count;   // entries of the level below
  uint tiles;   // ceil(count / kTile)
  uint shift;   // 6: voxels -> bricks; 3: cells -> parents
  uint unused;
} params;

const uint kTile = 4096u;

layout(std430, binding = 0) readonly buffer BelowKeys { uint64_t below_keys[]; };
layout(std430, binding = 1) readonly buffer BelowHashes { uint64_t below_hashes[]; };
layout(std430, binding = 2) buffer Firsts { uint firsts[]; };  // per cell: its first entry below
layout(std430, binding = 3) buffer Keys { uint64_t keys[]; };   // per cell
layout(std430, binding = 4) buffer Counts { uint counts[]; };   // per tile: cells starting there; total at [tiles]
layout(std430, binding = 5) buffer Hashes { uint64_t hashes[]; };

uint TileEnd(uint tile) { return min(params.count, (tile + 1u) * kTile); }
bool Head(uint i) { return i == 0u || (below_keys[i] >> params.shift) != (below_keys[i - 1u] >> params.shift); }
