// A dataset's voxelized shadows over HTTP (proto/PROTOCOL.md §3.2):
//   POST   /v1/datasets/{id}/shadows                          a shadows job (202, Location /v1/jobs/{job})
//   GET    /v1/datasets/{id}/shadows                          the current set's summary
//   DELETE /v1/datasets/{id}/shadows                          204
//   GET    /v1/datasets/{id}/shadows/tiles/{level}/{x}/{y}/{z} one tile's layer (SHADOW_FORMAT.md §2)
//   GET    /v1/datasets/{id}/shadows/dag                      the set's shadow DAG (SHADOW_FORMAT.md §1)
//   GET    /v1/datasets/{id}/shadows/query?x=&y=&z=           lit or shadowed at a point (shadow_query.h)
//
// Contract: one shadows job per dataset at a time (a second POST while one is queued or running is
// 409 naming it); a finished job replaces the set whole (Store::CommitShadows). Layers are answered
// as tiles are (strong ETag, 304, Range) except that a later POST may replace them, so they are
// `Cache-Control: no-cache` (revalidated by ETag), not immutable; so is the DAG. Queries answer from
// an in-memory copy of the DAG (ShadowQueryCache). Method and token checks are the
// caller's (Service::Route); CORS is added by Service.
#pragma once

#include <map>
#include <string>

#include "answers.h"
#include "jobs.h"
#include "metrics.h"
#include "shadow_query.h"
#include "store.h"

namespace pointdag::server {

class ShadowService {
 public:
  static constexpr const char* kRoute = "/v1/datasets/{id}/shadows";
  static constexpr const char* kTilesRoute = "/v1/datasets/{id}/shadows/tiles";
  static constexpr const char* kDagRoute = "/v1/datasets/{id}/shadows/dag";
  static constexpr const char* kQueryRoute = "/v1/datasets/{id}/shadows/query";

  ShadowService(Store& store, JobQueue& jobs, Metrics& metrics)
      : store_(store), jobs_(jobs), metrics_(metrics), queries_(store) {}

  HttpResponse Post(const HttpRequest& request, const std::string& dataset);
  HttpResponse Get(const std::string& dataset);
  HttpResponse Delete(const std::string& dataset);
  HttpResponse GetLayer(const HttpRequest& request, const std::string& dataset, const TileKey& key);
  HttpResponse GetDag(const HttpRequest& request, const std::string& dataset);
  HttpResponse Query(const std::string& dataset, const std::map<std::string, std::string>& query);
  // The dataset was deleted: its cached DAG goes.
  void ForgetDataset(const std::string& dataset) { queries_.Erase(dataset); }

 private:
  // 404 saying whether the dataset or its shadows are missing (or a store failure).
  HttpResponse NoShadows(const std::string& dataset, const std::string& route);
  // 404 for a dataset or set without a shadow DAG, saying which.
  HttpResponse NoShadowDag(const std::string& dataset, const std::string& route);

  Store& store_;
  JobQueue& jobs_;
  Metrics& metrics_;
  ShadowQueryCache queries_;
};

}  // namespace pointdag::server
