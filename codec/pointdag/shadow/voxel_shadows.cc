#include "pointdag/shadow/voxel_shadows.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <system_error>
#include <thread>

#include "pointdag/shadow/shadow_ray.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

constexpr size_t kMaxLights = 65535;  // counts are 16-bit
constexpr size_t kBlock = 512;        // voxels a worker takes at a time (Morton neighbours share bricks)

Status CheckLight(const Light& light) {
  RETURN_IF_ERROR(CheckShadowBias(light.bias_voxels));
  if (light.below_horizon) return Status::Ok();
  const auto& t = light.travel;
  if (!std::isfinite(t[0]) || !std::isfinite(t[1]) || !std::isfinite(t[2])) {
    return InvalidArgument("light direction has a NaN or infinite component");
  }
  if (t[0] == 0 && t[1] == 0 && t[2] == 0) return InvalidArgument("light direction (0, 0, 0) has no direction");
  return Status::Ok();
}

Status CheckDag(const Svdag& dag) {
  if (dag.depth < 2 || dag.depth > kMaxDepth) {
    return InvalidArgument("DAG depth " + std::to_string(dag.depth) + " is outside 2..21");
  }
  return Status::Ok();
}

int WorkerCount(int threads, size_t voxels) {
  size_t n = threads > 0 ? static_cast<size_t>(threads) : std::max(1u, std::thread::hardware_concurrency());
  n = std::min(n, (voxels + kBlock - 1) / kBlock);
  return static_cast<int>(std::max<size_t>(n, 1));
}

// Each voxel's answer depends on nothing but the voxel, so blocks go to whichever worker is free.
void CastAll(const Svdag& dag, const Light& light, const std::vector<uint64_t>& codes, int threads,
             std::vector<uint8_t>& shadowed) {
  std::atomic<size_t> next{0};
  auto work = [&] {
    ShadowRayCaster caster(dag, light.travel, light.bias_voxels);
    for (size_t begin; (begin = next.fetch_add(kBlock)) < codes.size();) {
      const size_t end = std::min(codes.size(), begin + kBlock);
      for (size_t i = begin; i < end; ++i) shadowed[i] = caster.Blocked(MortonDecode(codes[i])) ? 1 : 0;
    }
  };
  const int workers = WorkerCount(threads, codes.size());
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;  // no more threads to be had: the workers running take the remaining blocks
    }
  }
  work();
  for (auto& t : pool) t.join();
}

}  // namespace

bool RayMeetsCell(const std::array<double, 3>& origin, const std::array<double, 3>& travel,
                  const std::array<uint32_t, 3>& cell, double bias) {
  // Slab test on the closed cube; an axis the ray keeps must already lie within the slab.
  double t_lo = -std::numeric_limits<double>::infinity();
  double t_hi = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double lo = cell[a], hi = lo + 1.0;
    if (travel[a] == 0) {
      if (origin[a] < lo || origin[a] > hi) return false;
      continue;
    }
    const double toward = -travel[a];
    double ta = (lo - origin[a]) / toward, tb = (hi - origin[a]) / toward;
    if (ta > tb) std::swap(ta, tb);
    t_lo = std::max(t_lo, ta);
    t_hi = std::min(t_hi, tb);
  }
  return t_lo <= t_hi && t_hi > bias;
}

StatusOr<std::vector<uint8_t>> ShadowedVoxels(const Svdag& dag, const Light& light, int threads) {
  RETURN_IF_ERROR(CheckDag(dag));
  RETURN_IF_ERROR(CheckLight(light));
  const std::vector<uint64_t> codes = dag.MortonCodes();
  std::vector<uint8_t> shadowed(codes.size(), 1);
  if (!light.below_horizon) CastAll(dag, light, codes, threads, shadowed);
  return shadowed;
}

StatusOr<std::vector<uint16_t>> LitSampleCounts(const Svdag& dag, std::span<const Light> lights, int threads) {
  if (lights.size() > kMaxLights) {
    return InvalidArgument(std::to_string(lights.size()) + " light samples; at most 65535 are counted");
  }
  RETURN_IF_ERROR(CheckDag(dag));
  for (const Light& light : lights) RETURN_IF_ERROR(CheckLight(light));
  const std::vector<uint64_t> codes = dag.MortonCodes();
  std::vector<uint16_t> lit(codes.size(), 0);
  std::vector<uint8_t> shadowed(codes.size());
  for (const Light& light : lights) {
    if (light.below_horizon) continue;
    CastAll(dag, light, codes, threads, shadowed);
    for (size_t i = 0; i < codes.size(); ++i) lit[i] = static_cast<uint16_t>(lit[i] + (shadowed[i] ^ 1));
  }
  return lit;
}

}  // namespace pointdag
