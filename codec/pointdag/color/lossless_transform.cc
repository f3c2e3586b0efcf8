#include "pointdag/color/lossless_transform.h"

#include <array>

namespace pointdag::lossless {
namespace {

// Per order, the source channel (0 R, 1 G, 2 B) of the coder's G, R and B.
constexpr std::array<std::array<int, 3>, kChannelOrders> kSources = {
    {{1, 0, 2}, {1, 2, 0}, {0, 1, 2}, {0, 2, 1}, {2, 1, 0}, {2, 0, 1}}};

}  // namespace

bool LayoutOf(uint8_t byte, Layout& layout) {
  if ((byte & 7) >= kChannelOrders || byte > 15) return false;
  layout = {byte & 7, (byte & 8) != 0};
  return true;
}

Rgb8 Reorder(Rgb8 c, int order) {
  const std::array<uint8_t, 3> v = {c.r, c.g, c.b};
  const auto& from = kSources[static_cast<size_t>(order)];
  return Rgb8{v[static_cast<size_t>(from[1])], v[static_cast<size_t>(from[0])], v[static_cast<size_t>(from[2])]};
}

Rgb8 Restore(Rgb8 c, int order) {
  std::array<uint8_t, 3> v{};
  const auto& from = kSources[static_cast<size_t>(order)];
  v[static_cast<size_t>(from[0])] = c.g;
  v[static_cast<size_t>(from[1])] = c.r;
  v[static_cast<size_t>(from[2])] = c.b;
  return Rgb8{v[0], v[1], v[2]};
}

}  // namespace pointdag::lossless
