#include "pointdag/color/lossless_layout.h"

#include <algorithm>
#include <optional>
#include <utility>

#include "pointdag/color/lossless_mixing.h"
#include "pointdag/color/lossless_neighbourhood.h"

namespace pointdag::lossless {
namespace {

constexpr size_t kMinSample = 16384;

void Lay(std::span<const Rgb8> colors, size_t begin, size_t end, int order, std::span<Rgb8> laid) {
  for (size_t i = begin; i < end; ++i) laid[i] = Reorder(colors[i], order);
}

}  // namespace

std::vector<uint8_t> EncodeLaid(std::span<const Rgb8> colors, std::span<const uint64_t> morton, Layout layout) {
  std::vector<Rgb8> laid(colors.size());
  Lay(colors, 0, colors.size(), layout.order, laid);
  return EncodeMixed(laid, morton, layout.columns);
}

// The trials share what does not depend on the layout: the sample's neighbourhoods, found once
// with the columns (those without are a prefix of each), and two encoders, the best so far and the
// one on trial. The best goes on over the other colors instead of coding the sample again.
LaidOut EncodeChosenLayout(std::span<const Rgb8> colors, std::span<const uint64_t> morton) {
  const size_t n = std::min(colors.size(), std::max(kMinSample, colors.size() / 8));
  std::optional<NeighbourhoodSearch> search;
  std::optional<RecordedNeighbourhoods> sample;
  if (!morton.empty()) {
    search.emplace(morton, 3, true);
    sample.emplace(*search, n);
  }
  std::vector<Rgb8> laid(colors.size());
  const auto code_sample = [&](MixedEncoder& encoder, Layout layout) {
    Lay(colors, 0, n, layout.order, laid);
    for (size_t i = 0; i < n; ++i) encoder.Code(laid, i, sample ? sample->At(i, layout.columns) : Neighbourhood{});
    return encoder.FinishedSize();
  };
  MixedEncoder best(morton), trial(morton);
  Layout chosen;
  size_t best_size = code_sample(best, chosen);
  const auto consider = [&](Layout layout) {
    trial.Reset();
    const size_t size = code_sample(trial, layout);
    if (size < best_size) std::swap(best, trial), chosen = layout, best_size = size;
  };
  if (search) consider({0, true});
  const bool columns = chosen.columns;
  for (int order = 1; order < kChannelOrders; ++order) consider({order, columns});

  Lay(colors, 0, colors.size(), chosen.order, laid);
  sample.reset();
  if (search && !chosen.columns) search->DropColumns();
  for (size_t i = n; i < colors.size(); ++i) best.Code(laid, i, search ? search->Next(i) : Neighbourhood{});
  return {chosen, best.Finish()};
}

}  // namespace pointdag::lossless
