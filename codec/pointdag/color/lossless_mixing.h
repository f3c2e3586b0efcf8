// Lossless colors version 3 (proto/PDAG_FORMAT.md §3): version 2's prediction from the decoded
// neighbours, reaching to ±4 voxels for a voxel with fewer than 4 within ±2, and each residual's
// binary decisions coded with a logistic mix of four context models instead of one gamma code per
// context. What each part gained is in docs/benchmarks.md ("Lossless colors, version 3").
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pointdag/color/lossless_predict.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::lossless {

// Version 3's encoder, color by color, so that the layout trials (lossless_layout.h) can feed it
// neighbourhoods found once, size a prefix and go on with the best. `morton`: empty (each color
// predicted from the previous one) or one code per color, sorted and unique; must outlive this.
class MixedEncoder {
 public:
  explicit MixedEncoder(std::span<const uint64_t> morton);
  ~MixedEncoder();
  MixedEncoder(MixedEncoder&&) noexcept;
  MixedEncoder& operator=(MixedEncoder&&) noexcept;

  // Back to an empty stream, for another trial.
  void Reset();
  // Codes colors[i] after colors [0, i), predicted from `around` (empty without Morton codes);
  // `log`: where to keep the prediction too.
  void Code(std::span<const Rgb8> colors, size_t i, const Neighbourhood& around, Predicted* log = nullptr);
  // Codes colors[i] with the prediction `known` for these colors.
  void Replay(std::span<const Rgb8> colors, size_t i, const Predicted& known);
  // The bytes Finish() would return now.
  size_t FinishedSize() const;
  std::vector<uint8_t> Finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// The range-coded colors (the payload after its header). `columns` (version 4's column mode, with
// `morton` only): the predictions take the columns around each voxel too.
std::vector<uint8_t> EncodeMixed(std::span<const Rgb8> colors, std::span<const uint64_t> morton, bool columns = false);

// Decodes colors.size() colors into `colors`; false when `coded` does not end where they do.
bool DecodeMixed(std::span<const uint8_t> coded, std::span<Rgb8> colors, std::span<const uint64_t> morton,
                 bool columns = false);

}  // namespace pointdag::lossless
