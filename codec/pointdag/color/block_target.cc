#include "pointdag/color/block_target.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

#include "pointdag/color/color_metrics.h"
#include "pointdag/color/weight_choice.h"

namespace pointdag {
namespace {

// The sample: 16 runs of up to 2048 colors, at most 1/8 of the array; arrays too small for runs of
// 256 are not sampled (the first guess and the corrections do).
constexpr uint32_t kSampleRuns = 16, kLongestRun = 2048, kShortestRun = 256;
constexpr int kSampleSteps = 3;
constexpr double kSampleClose = 0.05;  // dB: a sample this close to the aim ends the prediction
constexpr double kClose = 0.03;        // dB above the target accepted without raising thresholds
constexpr double kAim = 0.01;          // dB above the target that corrections aim at
// A unit's error moves by at most 0.8x down or 1.4x up per round: more units, each changed less,
// keep thresholds closer to uniform (guanyin at 34 dB: 2.5% smaller than 0.5x / 2x on fewer units).
constexpr double kSpreadLower = 5.0, kSpreadRaise = 2.5;
constexpr int kRounds = 6;             // correction rounds before the last resort
// Rounds that may raise thresholds (bytes only; the later rounds' raises moved PSNR-Y by hundredths
// of a dB for 0.03-0.1 encodes each: autzen's tiles, IGN 0.25 m, tiny at 42 dB).
constexpr int kRaisingRounds = 3;
constexpr int kQuarterings = 3;        // a unit's threshold quartered this often before exact colors
constexpr uint32_t kUnitsWanted = 32, kSmallestUnit = 1024;  // correction units
constexpr double kLn10 = 2.302585092994046;
constexpr double kExactDb = 100.0;     // stands in for the infinite PSNR of exact colors
// Thresholds from 1e-3 (exact in practice) to 3e5 (above any 8-bit MSE: one block per macro block).
const double kMinLogT = std::log(1e-3), kMaxLogT = std::log(3e5);

// A run of colors encoded on its own: a correction unit (whole blocks inside one macro block), or a sample run.
struct Unit {
  uint32_t begin = 0, count = 0;
  double log_t = 0;  // ln of its threshold
  std::vector<ColorBlock> blocks;
  double sse = 0;  // luma squared error over its judged colors
  std::vector<uint8_t> weights;  // its colors' weights as the stream codes them (from `begin`)
};

class Judge {
 public:
  Judge(std::span<const Rgb8> colors, std::span<const uint64_t> judged) : colors_(colors), count_(colors.size()) {
    if (judged.empty()) return;
    weight_.assign(colors.size(), 0);
    for (uint64_t i : judged) ++weight_[i];
    count_ = judged.size();
  }

  // The decoder's reconstruction of `blocks` (their colors' weights from color `base` on) against
  // the input, in luma squared error.
  double Sse(std::span<const ColorBlock> blocks, std::span<const uint8_t> weights, uint32_t base) const {
    double sse = 0;
    for (const ColorBlock& b : blocks) {
      for (uint32_t i = b.start; i < b.start + b.length; ++i) {
        if (!weight_.empty() && weight_[i] == 0) continue;
        const Rgb8 c = colors_[i];
        const double dy = LumaBt709(c) - LumaBt709(Interpolate(b.ends, weights[i - base], b.bits));
        sse += (weight_.empty() ? 1.0 : weight_[i]) * dy * dy;
      }
    }
    return sse;
  }
  double Judged(uint32_t begin, uint32_t count) const {
    if (weight_.empty()) return count;
    return std::accumulate(weight_.begin() + begin, weight_.begin() + begin + count, 0.0);
  }
  double count() const { return static_cast<double>(count_); }

 private:
  std::span<const Rgb8> colors_;
  std::vector<uint32_t> weight_;  // how often each color is judged; empty: once each
  size_t count_;
};

// The blocks' weights are chosen rate-aware (weight_choice.h) at a price that follows the threshold,
// and their endpoints refitted for those weights (lion, guanyin, autzen 1-7 % smaller at equal PSNR-Y).
// The weights chosen for the final endpoints go to `weights` (from color `base` on): measuring the
// blocks (Judge::Sse) and writing them need not choose them again (10 % of a lion ingest's CPU was
// ChooseBlockWeights, a third of it choosing weights already chosen).
void Price(std::span<const Rgb8> colors, std::span<ColorBlock> blocks, double max_mse, std::span<uint8_t> weights,
           uint32_t base) {
  const uint32_t price = WeightRatePrice(max_mse, colors.size());
  tbb::parallel_for(size_t{0}, blocks.size(), [&](size_t k) {
    blocks[k].rate_price = price;
    RefitEnds(colors, blocks[k], weights.subspan(blocks[k].start - base, blocks[k].length));
  });
}

Status EncodeUnit(std::span<const Rgb8> colors, BlockLayout layout, const Judge& judge, Unit& unit) {
  const double max_mse = std::exp(unit.log_t);
  ASSIGN_OR_RETURN(unit.blocks, EncodeBlocks(colors.subspan(unit.begin, unit.count), layout, max_mse));
  for (ColorBlock& b : unit.blocks) b.start += unit.begin;
  unit.weights.resize(unit.count);
  Price(colors, unit.blocks, max_mse, unit.weights, unit.begin);
  unit.sse = judge.Sse(unit.blocks, unit.weights, unit.begin);
  return Status::Ok();
}

// Encodes the units in parallel; the first error, if any.
Status EncodeUnits(std::span<const Rgb8> colors, BlockLayout layout, const Judge& judge, std::span<Unit*> units) {
  std::vector<Status> status(units.size());
  tbb::parallel_for(size_t{0}, units.size(), [&](size_t k) { status[k] = EncodeUnit(colors, layout, judge, *units[k]); });
  for (const Status& s : status) RETURN_IF_ERROR(s);
  return Status::Ok();
}

double Psnr(double sse, double judged) { return judged > 0 ? std::min(PsnrFromMse(sse / judged), kExactDb) : kExactDb; }

struct Prediction {
  double log_t;
  double alpha = 1;  // the error grows as threshold^alpha
};

// The threshold whose sample PSNR-Y is target + kAim: a secant on log(threshold) from a multiple of
// the MSE the target allows where lion, guanyin and autzen meet it: 1.5 for the fixed rate, whose
// threshold bounds each block; 2.5 for the variable rate, whose cut prices bits with it
// (block_codec.cc; 1.5-3.1 at 34 and 42 dB).
StatusOr<Prediction> Predict(std::span<const Rgb8> colors, BlockLayout layout, const Judge& judge, double target,
                             double& encoded) {
  const double allowed = 255.0 * 255.0 / std::pow(10.0, target / 10.0);
  Prediction out{std::log((layout == BlockLayout::kVariableRate ? 2.5 : 1.5) * allowed)};
  const uint32_t run = std::min(kLongestRun, std::bit_floor(static_cast<uint32_t>(colors.size() / (8 * kSampleRuns))));
  if (run < kShortestRun) return out;
  std::vector<Unit> sample(kSampleRuns);
  double judged = 0;
  for (uint32_t k = 0; k < kSampleRuns; ++k) {
    const size_t centre = (2 * size_t{k} + 1) * colors.size() / (2 * kSampleRuns);
    sample[k].begin = static_cast<uint32_t>(centre - run / 2);
    sample[k].count = run;
    judged += judge.Judged(sample[k].begin, run);
  }
  if (judged == 0) return out;
  std::vector<Unit*> units;
  for (Unit& u : sample) units.push_back(&u);
  constexpr double kDefaultSlope = -10.0 / kLn10;  // dB per unit of ln(threshold) when alpha is 1
  // The slope from the first encode to the latest, the widest span: the curve is jagged at the
  // scale of one step (milk: 0.24 from the last step, 0.66 from the span).
  std::optional<std::pair<double, double>> first;  // (log_t, psnr)
  for (int step = 0; step < kSampleSteps; ++step) {
    for (Unit& u : sample) u.log_t = out.log_t;
    RETURN_IF_ERROR(EncodeUnits(colors, layout, judge, units));
    encoded += static_cast<double>(run * kSampleRuns) / static_cast<double>(colors.size());
    double sse = 0;
    for (const Unit& u : sample) sse += u.sse;
    const double psnr = Psnr(sse, judged);
    double slope = kDefaultSlope * out.alpha;
    if (first && first->first != out.log_t) {
      slope = std::clamp((psnr - first->second) / (out.log_t - first->first), 3 * kDefaultSlope, kDefaultSlope / 3);
      out.alpha = slope / kDefaultSlope;
    }
    if (std::abs(psnr - target - kAim) < kSampleClose) break;
    if (!first) first = {out.log_t, psnr};
    out.log_t = std::clamp(out.log_t + (target + kAim - psnr) / slope, kMinLogT, kMaxLogT);
  }
  return out;
}

}  // namespace

StatusOr<TargetBlocks> BlocksForTarget(std::span<const Rgb8> colors, std::span<const uint64_t> judged, BlockLayout layout,
                                       double target, std::optional<double> hint) {
  const Judge judge(colors, judged);
  TargetBlocks out;
  Prediction prediction{0};
  if (hint && *hint > 0 && std::isfinite(*hint)) {
    prediction.log_t = std::clamp(std::log(*hint), kMinLogT, kMaxLogT);
  } else {
    ASSIGN_OR_RETURN(prediction, Predict(colors, layout, judge, target, out.encodes));
  }

  // One encode of the whole array, cut into units at the first block start past every multiple of
  // the unit size (a power of two up to a macro block, so that every macro block starts a unit):
  // each unit can then be encoded again on its own.
  ASSIGN_OR_RETURN(std::vector<ColorBlock> all, EncodeBlocks(colors, layout, std::exp(prediction.log_t)));
  std::vector<uint8_t> all_weights(colors.size());
  Price(colors, all, std::exp(prediction.log_t), all_weights, 0);
  out.encodes += 1;
  const uint32_t unit_size = std::clamp<uint32_t>(std::bit_floor(static_cast<uint32_t>(colors.size() / kUnitsWanted)),
                                                  kSmallestUnit, kMacroBlockColors);
  std::vector<Unit> units;
  for (const ColorBlock& b : all) {
    if (units.empty() || b.start >= (units.back().begin / unit_size + 1) * unit_size) {
      units.push_back({b.start, 0, prediction.log_t, {}, 0, {}});
    }
    units.back().count += b.length;
    units.back().blocks.push_back(b);
  }
  tbb::parallel_for(size_t{0}, units.size(), [&](size_t m) {
    Unit& u = units[m];
    u.weights.assign(all_weights.begin() + u.begin, all_weights.begin() + u.begin + u.count);
    u.sse = judge.Sse(u.blocks, u.weights, u.begin);
  });
  double alpha = prediction.alpha;

  // Local corrections: scale the thresholds of the fewest units (largest error first) whose
  // error, scaled as threshold^alpha by at most 2x, moves the total to the aim.
  const double budget = judge.count() * 255.0 * 255.0 / std::pow(10.0, target / 10.0);
  const double aim = budget * std::pow(10.0, -kAim / 10.0);
  const auto total = [&] { return std::accumulate(units.begin(), units.end(), 0.0, [](double s, const Unit& u) { return s + u.sse; }); };
  const auto meets = [&](double sse) { return Psnr(sse, judge.count()) >= target; };
  std::vector<size_t> order(units.size());
  for (int round = 0; round < kRounds; ++round) {
    const double now = total();
    if (meets(now) && Psnr(now, judge.count()) - target < kClose) break;
    const double change = aim - now;  // < 0: lower thresholds, > 0: raise them
    if (change > 0 && round >= kRaisingRounds) break;  // the target is met
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return units[a].sse > units[b].sse; });
    std::vector<size_t> chosen;
    double chosen_sse = 0;
    for (size_t m : order) {
      if (units[m].sse <= 0) break;
      if (chosen_sse >= std::abs(change) * (change < 0 ? kSpreadLower : kSpreadRaise)) break;
      chosen.push_back(m);
      chosen_sse += units[m].sse;
    }
    if (chosen.empty()) break;  // nothing left to move (exact colors)
    const double factor = std::max(1 + change / chosen_sse, 0.02);
    std::vector<Unit> trials;
    for (size_t m : chosen) {
      Unit t{units[m].begin, units[m].count, units[m].log_t + std::log(factor) / alpha, {}, 0, {}};
      trials.push_back(std::move(t));
      out.encodes += static_cast<double>(units[m].count) / static_cast<double>(colors.size());
    }
    std::vector<Unit*> pointers;
    for (Unit& t : trials) pointers.push_back(&t);
    RETURN_IF_ERROR(EncodeUnits(colors, layout, judge, pointers));
    // What the error did, for the next round's exponent.
    double before = 0, after = 0;
    for (size_t k = 0; k < chosen.size(); ++k) before += units[chosen[k]].sse, after += trials[k].sse;
    if (before > 0 && after > 0 && factor != 1) alpha = std::clamp(std::log(after / before) * alpha / std::log(factor), 0.3, 3.0);
    double running = now;
    bool moved = false;
    for (size_t k = 0; k < chosen.size(); ++k) {
      Unit& u = units[chosen[k]];
      // Lowering keeps every smaller error; raising only what the total can still afford.
      const bool take = change < 0 ? trials[k].sse < u.sse : meets(running - u.sse + trials[k].sse);
      if (take) running += trials[k].sse - u.sse, u = std::move(trials[k]), moved = true;
    }
    if (!moved) break;  // the same choice again would change nothing
    // Raising only saves bytes: a raise that left the error no larger (the blocks already as coarse
    // as they go, or a jagged step) does no better the next round (autzen's 1,442-voxel tile in
    // bench --ingest ran all six rounds at one PSNR-Y, 7 encodes; tiny at 42 dB 5.9 -> 4.9).
    if (change > 0 && !(total() > now)) break;
  }
  // Last resort, largest error first, until the target is met: a unit's threshold quartered up to
  // kQuarterings times, then exact colors. (IGN 0.5 m at 38 dB: the one correction round lowered two
  // units' thresholds by 12 %, both errors grew, and one unit went straight to exact colors: +28 % bits.)
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return units[a].sse > units[b].sse; });
  for (size_t m : order) {
    double log_t = units[m].log_t;
    for (int step = 0; step <= kQuarterings && !meets(total()); ++step) {
      log_t = step < kQuarterings ? log_t - std::log(4.0) : -std::numeric_limits<double>::infinity();
      Unit trial{units[m].begin, units[m].count, log_t, {}, 0, {}};
      RETURN_IF_ERROR(EncodeUnit(colors, layout, judge, trial));
      out.encodes += static_cast<double>(units[m].count) / static_cast<double>(colors.size());
      if (step == kQuarterings || trial.sse < units[m].sse) units[m] = std::move(trial);
    }
    if (meets(total())) break;
  }
  double log_sum = 0, counted = 0;
  for (const Unit& u : units) {
    out.blocks.insert(out.blocks.end(), u.blocks.begin(), u.blocks.end());
    out.weights.insert(out.weights.end(), u.weights.begin(), u.weights.end());
    if (std::isfinite(u.log_t)) log_sum += u.log_t * u.count, counted += u.count;
  }
  out.max_mse = counted > 0 ? std::exp(log_sum / counted) : 0;
  return out;
}

}  // namespace pointdag
