// Stage 10b (issue #16; the seed's Paper I, after Sintorn et al. 2014): a light-space grid of
// lit / shadowed / undefined cells, compressed as a DAG.
//
// Light space: z' along the light's travel, x' and y' perpendicular (a fixed choice per direction),
// a cube covering the dataset's grid cube in those axes, 2^light_depth cells per side. With
// light_depth = dataset depth + 2 a cell's diagonal is at most 0.75 voxel, so no cell holds two voxel
// centres: the cell holding a voxel's centre stores that voxel's exact answer (voxel_shadows.h).
// Cells nobody queries are undefined (the paper's rules; see the implementation for which) and
// the build resolves them to whatever merges best: a subtree whose defined cells are all lit
// becomes empty, all shadowed becomes full, and identical subtrees are merged with hashes
// (Paper I: built chunk by chunk and merged, so memory stays bounded by a chunk).
//
// Query: Shadowed(p) for any point of the dataset's grid (grid units) by DAG traversal; exact for
// every voxel centre of the dataset, whatever the relaxation chose elsewhere.
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

struct ShadowBuildOptions {
  int extra_levels = 2;        // light_depth = dag.depth + extra_levels
  bool relax_undefined = true;  // false: undefined cells count as lit (for measuring the relaxation)
  // With relax_undefined: undefined cells of mixed bricks and nodes are chosen to repeat a brick or
  // node already built where one fits (Kämpe et al. 2015); false: they become lit.
  bool match_undefined = true;
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
