#include "pointdag/color/lossless_layout.h"

#include <algorithm>
#include <array>
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
// with the columns (those without are a prefix of each); the predictions of each lead channel,
// replayed swapped in the order with the same lead; and two encoders, the best so far and the one
// on trial. The best goes on over the other colors instead of coding the sample again.
LaidOut EncodeChosenLayout(std::span<const Rgb8> colors, std::span<const uint64_t> morton) {
  const size_t n = std::min(colors.size(), std::max(kMinSample, colors.size() / 8));
  std::optional<NeighbourhoodSearch> search;
  std::optional<RecordedNeighbourhoods> sample;
  if (!morton.empty()) {
    search.emplace(morton, 3, true);
    sample.emplace(*search, n);
  }
  std::vector<Rgb8> laid(colors.size());
  // Codes the sample in `layout`, keeping its predictions in `log` or replaying `known`'s swapped.
  const auto code_sample = [&](MixedEncoder& encoder, Layout layout, std::vector<Predicted>* log, const std::vector<Predicted>* known) {
    Lay(colors, 0, n, layout.order, laid);
    for (size_t i = 0; i < n; ++i) {
      if (known != nullptr) {
        encoder.Replay(laid, i, Swapped((*known)[i]));
      } else {
        encoder.Code(laid, i, sample ? sample->At(i, layout.columns) : Neighbourhood{}, &(*log)[i]);
      }
    }
    return encoder.FinishedSize();
  };
  std::array<std::vector<Predicted>, 2> logs = {std::vector<Predicted>(n), std::vector<Predicted>(n)};  // by columns
  MixedEncoder best(morton), trial(morton);
  Layout chosen;
  size_t best_size = code_sample(best, chosen, &logs[0], nullptr);
  const auto consider = [&](Layout layout, std::vector<Predicted>* log, const std::vector<Predicted>* known) {
    trial.Reset();
    const size_t size = code_sample(trial, layout, log, known);
    if (size < best_size) std::swap(best, trial), chosen = layout, best_size = size;
  };
  if (search) consider({0, true}, &logs[1], nullptr);
  // Orders 2k and 2k + 1 share their lead (and the others swapped): one predicts, the other replays.
  const bool columns = chosen.columns;
  std::vector<Predicted>& lead = logs[columns ? 1 : 0];
  for (int order = 1; order < kChannelOrders; ++order) {
    if (order % 2 == 1) {
      consider({order, columns}, nullptr, &lead);
    } else {
      consider({order, columns}, &lead, nullptr);
    }
  }

  Lay(colors, 0, colors.size(), chosen.order, laid);
  sample.reset();
  if (search && !chosen.columns) search->DropColumns();
  for (size_t i = n; i < colors.size(); ++i) best.Code(laid, i, search ? search->Next(i) : Neighbourhood{});
  return {chosen, best.Finish()};
}

}  // namespace pointdag::lossless
