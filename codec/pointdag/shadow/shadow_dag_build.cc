// Which light-space cells are defined (shadow_dag.h): the cell holding each voxel's centre, with
// that voxel's exact answer (voxel_shadows.h). Every other cell is undefined: cells inside a
// voxel's cube that hold no centre are inside geometry, and free space is never queried either,
// as in Kämpe et al. 2015, where only surfaces look up their shadow; unless define_free_space asks
// for free space too (shadow_free_space.cc).
#include <algorithm>
#include <chrono>

#include "pointdag/shadow/shadow_dag_impl.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {

StatusOr<ShadowDag> BuildShadowDag(const Svdag& dag, const Light& light, const ShadowBuildOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.extra_levels < 2 || options.extra_levels > 8) return InvalidArgument("extra_levels must be in 2..8");
  auto impl = std::make_unique<ShadowDag::Impl>();
  auto frame = LightFrame::Create(light.travel, dag.depth, dag.depth + options.extra_levels);
  // Below the horizon every answer is "shadowed" whatever the travel; a NaN one still gets a frame.
  if (!frame.ok() && light.below_horizon) frame = LightFrame::Create({0, 0, -1}, dag.depth, dag.depth + options.extra_levels);
  RETURN_IF_ERROR(frame.status());
  impl->frame = *frame;
  impl->below_horizon = light.below_horizon;
  ASSIGN_OR_RETURN(const std::vector<uint8_t> shadowed, ShadowedVoxels(dag, light));

  std::vector<uint64_t> cells;
  cells.reserve(shadowed.size());
  size_t i = 0;
  bool inside = true;
  dag.ForEachVoxel([&](uint64_t morton) {
    const auto [x, y, z] = MortonDecode(morton);
    const auto cell = impl->frame.Cell({x + 0.5, y + 0.5, z + 0.5});
    inside = inside && cell.has_value() && i < shadowed.size();
    if (inside) cells.push_back(MortonEncode((*cell)[0], (*cell)[1], (*cell)[2]) << 1 | (shadowed[i] & 1));
    ++i;
  });
  if (!inside || i != shadowed.size()) return Internal("voxel centres and exact shadows disagree on the voxels");
  std::sort(cells.begin(), cells.end());
  const uint64_t input_bytes = cells.capacity() * 8 + shadowed.capacity();
  if (options.define_free_space) {
    RETURN_IF_ERROR(BuildFreeSpaceArrays(dag, cells, options, *impl));
  } else {
    RETURN_IF_ERROR(BuildShadowArrays(cells, impl->frame.light_depth(), options, *impl));
  }

  impl->stats.surface_voxels = shadowed.size();
  impl->stats.shadowed_voxels = static_cast<uint64_t>(std::count(shadowed.begin(), shadowed.end(), 1));
  impl->stats.build_peak_bytes += input_bytes;
  impl->stats.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return ShadowDag(std::move(impl));
}

}  // namespace pointdag
