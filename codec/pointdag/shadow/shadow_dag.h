// Stage 10b (issue #16; the seed's Paper I, after Sintorn et al. 2014): a light-space grid of
// lit / shadowed / undefined cells, compressed as a DAG.
//
// Light space (light_frame.h): z' along the light's travel, x' and y' perpendicular (a fixed choice
// per direction), a cube covering the dataset's grid cube in those axes, 2^light_depth cells per
// side, light_depth <= 21. With light_depth = dataset depth + 2 a cell's diagonal is at most 0.75
// voxel, so no cell holds two voxel centres: the cell holding a voxel's centre stores that voxel's
// exact answer (voxel_shadows.h). Every other cell is undefined (shadow_dag_build.cc): inside a
// voxel's cube it is inside geometry, and free space is never queried, as in Kämpe et al. 2015
// where only surfaces look up their shadow (ShadowBuildOptions::define_free_space defines the air
// too, at a cost measured in docs/benchmarks.md). The build resolves undefined cells to whatever merges
// best: a subtree whose defined cells are all lit becomes all lit, all shadowed becomes all
// shadowed, mixed ones follow ShadowBuildOptions::fill, and identical subtrees are merged with
// hashes confirmed by comparison (Paper I's hashes, in one streaming bottom-up pass over the
// defined cells in light-space Morton order: the temporaries are one pending node per level, so no
// chunks are needed to bound memory; see shadow_dag_builder.cc). Only cells holding a defined cell
// are visited: O(voxels · light_depth), never the 2^(3·light_depth) grid.
//
// Query: Shadowed(p) for any point of the dataset's grid (grid units) by DAG traversal; exact for
// every voxel centre of the dataset, whatever the relaxation chose elsewhere; a point outside the
// light cube (so outside the grid) is lit, unless the light is below the horizon.
//
// Sizes: stats count the resident arrays as the papers do (4-byte node words, 8-byte leaves); the
// dense grid (one bit per cell, 2^(3·light_depth-3) bytes) and the shadow map (2^(2·light_depth)
// texels of 4 bytes) are exact in 64 bits since light_depth <= 21.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pointdag/dag/svdag.h"
#include "pointdag/shadow/light.h"
#include "pointdag/status.h"

namespace pointdag {

// With relax_undefined, how the undefined cells of a subtree holding both lit and shadowed cells
// are chosen (measured in docs/benchmarks.md, "Shadow DAG").
enum class UndefinedFill : uint8_t {
  kLit,       // all lit
  kMajority,  // as most defined cells of the brick, or most all-lit / all-shadowed children of the node; lit on a tie
  kMatch,     // to repeat a brick or node already built where one fits (Kämpe et al. 2015's aim), else lit
};

struct ShadowBuildOptions {
  int extra_levels = 2;        // light_depth = dag.depth + extra_levels, 2..8
  bool relax_undefined = true;  // false: undefined cells count as lit (for measuring the relaxation)
  UndefinedFill fill = UndefinedFill::kMajority;
  // true: cells whose centre is outside every voxel cube are defined too, from a light-space depth map
  // of the cubes (shadow_free_space.cc), so a point in the air is answered truly at its cell's centre;
  // only cells inside cubes stay undefined. Larger and slower to build; relax_undefined and fill do
  // not apply. false (default): only the voxel centres are defined, as only surfaces are queried.
  bool define_free_space = false;
  // Bits of the subtree hash that are kept; tests narrow it to force collisions (answers must not change).
  uint64_t hash_mask = ~uint64_t{0};
};

struct ShadowDagStats {
  uint64_t surface_voxels = 0;   // voxels of the dataset
  uint64_t shadowed_voxels = 0;  // of them, in shadow
  uint64_t shadow_dag_bytes = 0;   // resident size of the DAG
  uint64_t dense_grid_bytes = 0;   // one bit per light-space cell
  uint64_t shadow_map_bytes = 0;   // a plain shadow map of the same resolution: 4-byte depth per texel
  int light_depth = 0;
  double build_seconds = 0;
  uint64_t build_peak_bytes = 0;   // own accounting: the largest the build's arrays got together
};

class ShadowDag {
 public:
  ShadowDag();
  ShadowDag(ShadowDag&&) noexcept;
  ShadowDag& operator=(ShadowDag&&) noexcept;
  ~ShadowDag();

  // Lit (false) or shadowed (true) at a point of the dataset's grid, in grid units.
  bool Shadowed(const std::array<double, 3>& grid_point) const;
  const ShadowDagStats& stats() const;

  // A self-contained byte form (spec: proto/SHADOW_FORMAT.md) and its hostile-input-safe reader.
  std::vector<uint8_t> Serialize() const;
  static StatusOr<ShadowDag> Deserialize(std::span<const uint8_t> bytes);

  struct Impl;
  explicit ShadowDag(std::unique_ptr<Impl> impl);

 private:
  std::unique_ptr<Impl> impl_;
};

StatusOr<ShadowDag> BuildShadowDag(const Svdag& dag, const Light& light, const ShadowBuildOptions& options = {});

}  // namespace pointdag
