// Shared by the voxel reduction kernels (voxel_*.comp): sort points by Morton code (LSD radix sort,
// 8 bits a pass), then one voxel per distinct code with the rounded mean of its points' colors,
// as ReduceChunk in codec/pointdag/voxelize/voxelizer.cc does on the CPU (keep the two in step).
// Work is cut into tiles of kTile points walked by one invocation each, so that no invocation runs
// more than 65535 loop iterations (lavapipe stops loops there; see block_common.glsl).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(push_constant) uniform Params {
  uint count;     // points
  uint tiles;     // ceil(count / kTile)
  uint shift;     // radix pass: the digit's lowest bit; voxel_scan: where the scanned run starts
  uint divisor;   // 1 for 8-bit colors, 257 for 16-bit ones; voxel_scan: how many values
} params;

const uint kTile = 4096u;
const uint kDigits = 256u;

// Radix passes bind the source at 0-1 and the destination at 2-3, swapping them between passes.
layout(std430, binding = 0) buffer SourceKeys { uvec2 src_keys[]; };    // Morton code: low, high word
layout(std430, binding = 1) buffer SourcePoints { uint src_points[]; };  // index of the point
layout(std430, binding = 2) buffer DestKeys { uvec2 dst_keys[]; };
layout(std430, binding = 3) buffer DestPoints { uint dst_points[]; };
// Radix: per digit and tile counts (digit-major), then per digit bases. Reduction: per tile voxel
// counts, then the voxel total at [tiles].
layout(std430, binding = 4) buffer Counts { uint counts[]; };
layout(std430, binding = 5) readonly buffer Colors { uvec2 colors[]; }; // per point: r | g << 16, b
layout(std430, binding = 6) buffer Sums { uint sums[]; };               // per voxel: r, g, b as (low, high), points
layout(std430, binding = 7) buffer Voxels { uvec4 voxels[]; };          // per voxel: code low, high, r | g << 8 | b << 16

uint TileEnd(uint tile) { return min(params.count, (tile + 1u) * kTile); }
bool SameKey(uvec2 a, uvec2 b) { return a.x == b.x && a.y == b.y; }
