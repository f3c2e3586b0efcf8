// Point queries against a dataset's shadow DAG (GET /v1/datasets/{id}/shadows/query, proto/PROTOCOL.md §3.2).
//
// Contract: the stored shadow DAG of the dataset's current set (Store::GetShadowDag) is read once,
// checked against its checksum, deserialized and kept in memory with the dataset's grid and the
// occupancy of its finest voxels (an Svdag built from the stored finest tiles, for "exact"). Every
// query first compares the stored DAG's etag with the cached one, so a set replaced by a later job
// or deleted is never answered from the old copy; Erase() drops an entry at once (DELETE routes).
// Thread-safe; loads happen outside the lock (two racing loads of one dataset are harmless).
#pragma once

#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include <nlohmann/json.hpp>

#include "pointdag/dag/svdag.h"
#include "pointdag/shadow/shadow_dag.h"
#include "store.h"

namespace pointdag::server {

struct QueryableShadows {
  std::string etag;                // of the stored DAG this was read from
  ShadowDag dag;
  Svdag voxels;                    // the dataset's finest voxels (occupancy only)
  std::array<double, 3> origin{};  // the grid's minimum corner in the dataset's frame (metadata bounds.min)
  double voxel_size = 1;
};

class ShadowQueryCache {
 public:
  explicit ShadowQueryCache(Store& store) : store_(store) {}

  // nullptr: the dataset has no shadow DAG (no set, a sun-hours set, or one stored before DAGs
  // were kept). kCorrupt when the stored DAG fails its checksum or does not read.
  StatusOr<std::shared_ptr<const QueryableShadows>> Get(const std::string& dataset);
  void Erase(const std::string& dataset);

 private:
  StatusOr<std::shared_ptr<const QueryableShadows>> Load(const std::string& dataset);

  Store& store_;
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<const QueryableShadows>> entries_;
};

// The answer to ?x=&y=&z= (dataset frame): for the voxel cell holding the point, {"shadowed",
// "exact" (the cell is a voxel of the dataset: then "shadowed" is its answer under the issue's
// definition with the set's bias; else free space, which the DAG does not define), "voxel" [i, j, k],
// "centre" [x, y, z] (the cell's centre, where the DAG was asked)}. kInvalidArgument for a missing
// or non-numeric coordinate, NaN or infinity, or a point outside the grid's cube.
StatusOr<nlohmann::json> AnswerShadowQuery(const QueryableShadows& shadows, const std::map<std::string, std::string>& query);

}  // namespace pointdag::server
