// A shadows job (POST /v1/datasets/{id}/shadows, proto/PROTOCOL.md §3.2): the dataset's finest
// voxels from its stored finest-level tiles, the lights of the stored request (shadow_request.h),
// the exact lit count of every voxel (voxel_shadows.h), every tile's layer (shadow_layer.h), and
// one commit of the whole set with the job's done state (Store::CommitShadows).
//
// Contract: returns "" once the set is committed, else the failure's reason (the dataset deleted
// meanwhile, a stored tile that does not decode, the store refusing the commit); nothing is written
// then, so the dataset keeps its previous set. Every layer is checked against the tile it belongs to
// (same key, same voxel count) before the commit. Safe to run again from the start (a resumed job).
#pragma once

#include <string>

#include "store.h"

namespace pointdag::server {

std::string RunShadowJob(Store& store, const JobRecord& job);

}  // namespace pointdag::server
