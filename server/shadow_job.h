// A shadows job (POST /v1/datasets/{id}/shadows, proto/PROTOCOL.md §3.2): the dataset's finest
// voxels from its stored finest-level tiles, the lights of the stored request (shadow_request.h),
// the exact lit count of every voxel (voxel_shadows.h), every tile's layer (shadow_layer.h), for one
// light (a direction or one sun time) the shadow DAG of the finest voxels (shadow_dag.h, what
// GET .../shadows/dag and .../shadows/query answer from; exact at voxel centres, so the one light's
// lit counts are read from it instead of casting every ray twice), and one commit of the whole set
// with the job's done state (Store::CommitShadows). A sun-hours set has no shadow DAG: its answer is a count
// per voxel, which one lit/shadowed DAG cannot hold, and no single sun of the span stands for it.
//
// Contract: returns "" once the set is committed, else the failure's reason (the dataset deleted
// meanwhile, a stored tile that does not decode, the store refusing the commit); nothing is written
// then, so the dataset keeps its previous set. Every layer is checked against the tile it belongs to
// (same key, same voxel count) before the commit. Safe to run again from the start (a resumed job).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "store.h"

namespace pointdag::server {

struct FinestVoxels {
  int depth = 0, tile_depth = 0, levels = 0;
  std::vector<uint64_t> morton;            // sorted
  std::map<TileKey, uint64_t> tile_voxels;  // every tile of every level
};

// The dataset's finest voxels, from its finest-level tiles' geometry (colors are not decoded);
// kCorrupt for metadata or tiles that disagree. Also what the shadow queries' occupancy is built from.
StatusOr<FinestVoxels> LoadFinestVoxels(Store& store, const std::string& dataset, const nlohmann::json& meta);

std::string RunShadowJob(Store& store, const JobRecord& job);

}  // namespace pointdag::server
