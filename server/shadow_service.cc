#include "shadow_service.h"

#include <algorithm>

#include "pointdag/json_text.h"
#include "shadow_request.h"

namespace pointdag::server {
namespace {

// As a tile is answered, but a later POST replaces the set under the same URL: revalidated by its
// ETag rather than kept for a year.
HttpResponse RevalidatedAnswer(const HttpRequest& request, const StoredTile& body, const std::string& content_type,
                               const std::string& route) {
  HttpResponse r = ImmutableAnswer(request, body, content_type, route);
  for (auto& [name, value] : r.headers) {
    if (name == "Cache-Control") value = "no-cache";
  }
  return r;
}

}  // namespace

HttpResponse ShadowService::Post(const HttpRequest& request, const std::string& dataset) {
  const auto meta = store_.GetDataset(dataset);
  if (!meta.ok()) return StoreFailureAnswer(meta.status(), kRoute);
  if (!*meta) return FailAnswer(404, "no dataset " + dataset, kRoute);
  const auto body = ParseJson(request.body);
  if (!body.ok()) return FailAnswer(400, "the body is not JSON: " + body.status().message(), kRoute);
  const auto plan = PlanShadows(*body, **meta);
  if (!plan.ok()) return FailAnswer(400, plan.status().message(), kRoute);
  const auto queue_full = [&] {
    HttpResponse r = FailAnswer(503, "the job queue is full; try again later", kRoute);
    r.SetHeader("Retry-After", "30");
    return r;
  };
  if (jobs_.full()) return queue_full();
  JobRecord job;
  job.id = NewId();
  job.kind = "shadows";
  job.dataset_id = dataset;
  job.params = plan->request;
  const auto existing = store_.CreateShadowJob(job);
  if (!existing.ok()) return StoreFailureAnswer(existing.status(), kRoute);
  if (*existing) {
    HttpResponse r = FailAnswer(409, "a shadows job for dataset " + dataset + " is already queued or running: /v1/jobs/" +
                                         **existing + "; post again once it has ended", kRoute);
    r.SetHeader("Location", "/v1/jobs/" + **existing);
    return r;
  }
  if (!jobs_.Submit(job.id)) {
    (void)store_.SetJobState(job.id, "failed", "the job queue was full");
    return queue_full();
  }
  const auto stored = store_.GetJob(job.id);  // with its times; the job as sent when the read fails
  HttpResponse r = JsonAnswer(202, JobJson(stored.ok() && *stored ? **stored : job), kRoute);
  r.SetHeader("Location", "/v1/jobs/" + job.id);
  return r;
}

HttpResponse ShadowService::NoShadows(const std::string& dataset, const std::string& route) {
  return NotFoundAnswer(store_, dataset,
                        "dataset " + dataset + " has no shadows (POST /v1/datasets/" + dataset + "/shadows computes them)", route);
}

HttpResponse ShadowService::Get(const std::string& dataset) {
  const auto summary = store_.GetShadows(dataset);
  if (!summary.ok()) return StoreFailureAnswer(summary.status(), kRoute);
  return *summary ? JsonAnswer(200, **summary, kRoute) : NoShadows(dataset, kRoute);
}

HttpResponse ShadowService::Delete(const std::string& dataset) {
  const auto deleted = store_.DeleteShadows(dataset);
  if (!deleted.ok()) return StoreFailureAnswer(deleted.status(), kRoute);
  queries_.Erase(dataset);
  if (!*deleted) return NoShadows(dataset, kRoute);
  HttpResponse r;
  r.status = 204;
  r.route = kRoute;
  return r;
}

HttpResponse ShadowService::GetLayer(const HttpRequest& request, const std::string& dataset, const TileKey& key) {
  const std::string address = TileAddress(key);
  const auto stored = store_.GetShadowTile(dataset, key);
  if (!stored.ok()) return StoreFailureAnswer(stored.status(), kTilesRoute);
  if (!*stored) {
    const auto summary = store_.GetShadows(dataset);
    if (!summary.ok()) return StoreFailureAnswer(summary.status(), kTilesRoute);
    if (!*summary) return NoShadows(dataset, kTilesRoute);
    return FailAnswer(404, "no tile " + address + " in this dataset", kTilesRoute);
  }
  if (auto corrupt = RefuseCorruptTile(**stored, dataset, "shadows/tiles/" + address, metrics_, kTilesRoute)) return *corrupt;
  return RevalidatedAnswer(request, **stored, "application/vnd.pointdag.shadow", kTilesRoute);
}

HttpResponse ShadowService::NoShadowDag(const std::string& dataset, const std::string& route) {
  const auto summary = store_.GetShadows(dataset);
  if (!summary.ok()) return StoreFailureAnswer(summary.status(), route);
  if (!*summary) return NoShadows(dataset, route);
  return FailAnswer(404, "the shadow set of dataset " + dataset + " has no shadow DAG (sun hours have none; "
                         "POST a direction or a time for one)", route);
}

HttpResponse ShadowService::GetDag(const HttpRequest& request, const std::string& dataset) {
  const auto stored = store_.GetShadowDag(dataset);
  if (!stored.ok()) return StoreFailureAnswer(stored.status(), kDagRoute);
  if (!*stored) return NoShadowDag(dataset, kDagRoute);
  if (auto corrupt = RefuseCorruptTile(**stored, dataset, "shadows/dag", metrics_, kDagRoute)) return *corrupt;
  return RevalidatedAnswer(request, **stored, "application/vnd.pointdag.shadow-dag", kDagRoute);
}

HttpResponse ShadowService::Query(const std::string& dataset, const std::map<std::string, std::string>& query) {
  const auto shadows = queries_.Get(dataset);
  if (!shadows.ok()) {
    if (shadows.status().code() == StatusCode::kCorrupt) return FailAnswer(500, shadows.status().message(), kQueryRoute);
    return StoreFailureAnswer(shadows.status(), kQueryRoute);
  }
  if (!*shadows) return NoShadowDag(dataset, kQueryRoute);
  const auto answer = AnswerShadowQuery(**shadows, query);
  if (!answer.ok()) return FailAnswer(400, answer.status().message(), kQueryRoute);
  return JsonAnswer(200, *answer, kQueryRoute);
}

}  // namespace pointdag::server
