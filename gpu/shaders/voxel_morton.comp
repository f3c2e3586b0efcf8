#version 450
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// Morton codes of integer cells, one invocation per point, as MortonEncode in
// codec/pointdag/voxelize/morton.h: bits (3i+2, 3i+1, 3i) hold (x_i, y_i, z_i).
layout(local_size_x = 64) in;

layout(push_constant) uniform Params { uint count; } params;

layout(std430, binding = 0) readonly buffer Cells { uint cells[]; };  // x, y, z per point
layout(std430, binding = 1) writeonly buffer Codes { uint64_t codes[]; };

uint64_t Spread(uint v) {
  uint64_t x = uint64_t(v & 0x1FFFFFu);
  x = (x | x << 32) & 0x1F00000000FFFFul;
  x = (x | x << 16) & 0x1F0000FF0000FFul;
  x = (x | x << 8) & 0x100F00F00F00F00Ful;
  x = (x | x << 4) & 0x10C30C30C30C30C3ul;
  x = (x | x << 2) & 0x1249249249249249ul;
  return x;
}

void main() {
  const uint i = gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u + gl_GlobalInvocationID.x;
  if (i >= params.count) return;
  codes[i] = Spread(cells[3u * i]) << 2 | Spread(cells[3u * i + 1u]) << 1 | Spread(cells[3u * i + 2u]);
}
