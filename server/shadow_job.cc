#include "shadow_job.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <span>
#include <map>

#include "pointdag/dag/dag_builder.h"
#include "pointdag/pipeline.h"
#include "pointdag/shadow/shadow_dag.h"
#include "pointdag/shadow/shadow_layer.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/morton.h"
#include "answers.h"
#include "shadow_request.h"

namespace pointdag::server {
namespace {

double Now() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

}  // namespace

StatusOr<FinestVoxels> LoadFinestVoxels(Store& store, const std::string& dataset, const nlohmann::json& meta) {
  FinestVoxels out;
  const auto int_member = [&](const char* name, int low, int high) -> StatusOr<int> {
    if (!meta.contains(name) || !meta[name].is_number_integer()) return Corrupt(std::string("the dataset's metadata lacks ") + name);
    const auto v = meta[name].get<int64_t>();
    if (v < low || v > high) return Corrupt(std::string("the dataset's ") + name + " is out of range");
    return static_cast<int>(v);
  };
  ASSIGN_OR_RETURN(out.depth, int_member("depth", 2, kMaxDepth));
  ASSIGN_OR_RETURN(out.tile_depth, int_member("tile_depth", 2, 8));
  ASSIGN_OR_RETURN(out.levels, int_member("levels", 1, kMaxDepth));
  if (out.levels != out.depth - out.tile_depth + 1) return Corrupt("the dataset's depth, tile_depth and levels disagree");
  std::vector<TileKey> unused;
  ASSIGN_OR_RETURN(const std::vector<HierarchyEntry> tiles, store.TilesBelow(dataset, TileKey{}, out.levels - 1, unused));
  std::vector<TileKey> finest;
  for (const HierarchyEntry& e : tiles) {
    out.tile_voxels[e.key] = e.voxels;
    if (e.key.level == out.levels - 1) finest.push_back(e.key);
  }
  std::sort(finest.begin(), finest.end(),
            [](const TileKey& a, const TileKey& b) { return MortonEncode(a.x, a.y, a.z) < MortonEncode(b.x, b.y, b.z); });
  DecodeLimits limits;
  limits.max_voxels = std::min(limits.max_voxels, uint64_t{1} << (3 * out.tile_depth));
  for (const TileKey& key : finest) {
    ASSIGN_OR_RETURN(const std::optional<StoredTile> stored, store.GetTile(dataset, key));
    const std::string address = TileAddress(key);
    if (!stored) return Corrupt("tile " + address + " vanished while it was read");
    if (TileEtag(stored->bytes) != stored->etag) return Corrupt("tile " + address + " does not match its checksum; run pointdagd --check");
    auto decoded = [&]() -> StatusOr<DecodedPdag> {
      ASSIGN_OR_RETURN(PdagFile file, ParsePdag(stored->bytes));
      file.colors.clear();
      return DecodePdag(file, limits);
    }();
    if (!decoded.ok()) return Corrupt("tile " + address + " does not decode: " + decoded.status().ToString());
    if (decoded->grid.depth != out.tile_depth || decoded->grid.morton.size() != out.tile_voxels[key]) {
      return Corrupt("tile " + address + " holds other voxels than its hierarchy entry says");
    }
    const uint64_t tile_code = MortonEncode(key.x, key.y, key.z) << (3 * out.tile_depth);
    for (uint64_t local : decoded->grid.morton) out.morton.push_back(tile_code | local);
  }
  if (out.morton.empty()) return Corrupt("the dataset has no finest-level tiles");
  return out;
}

namespace {

// One light: its shadow DAG (the light's only ray pass: BuildShadowDag runs ShadowedVoxels for the
// cells of the voxel centres, where the DAG is exact), its figures in the summary; sun hours: none
// (their figures null).
StatusOr<std::optional<ShadowDag>> ShadowDagOf(const Svdag& dag, const ShadowPlan& plan, nlohmann::json& summary) {
  for (const char* key : {"shadow_dag_bytes", "shadow_dag_file_bytes", "dense_grid_bytes", "shadow_map_bytes",
                          "light_depth", "build_seconds"}) {
    summary[key] = nullptr;
  }
  if (plan.lights.size() != 1) return std::optional<ShadowDag>();
  ASSIGN_OR_RETURN(ShadowDag shadow, BuildShadowDag(dag, plan.lights.front()));
  const ShadowDagStats& stats = shadow.stats();
  summary["shadow_dag_bytes"] = stats.shadow_dag_bytes;
  summary["dense_grid_bytes"] = stats.dense_grid_bytes;
  summary["shadow_map_bytes"] = stats.shadow_map_bytes;
  summary["light_depth"] = stats.light_depth;
  summary["build_seconds"] = stats.build_seconds;
  return std::optional<ShadowDag>(std::move(shadow));
}

// Per voxel (`morton`, the DAG's voxels in order), how many of the plan's lights light it. One
// light: read from its shadow DAG at each voxel's centre. Several go in about 20 groups, each
// reported to `done(fraction)`, so that a long sun-hours job shows its progress.
StatusOr<std::vector<uint16_t>> LitCounts(const Svdag& dag, const std::vector<uint64_t>& morton, const ShadowPlan& plan,
                                          const std::optional<ShadowDag>& shadow, const std::function<void(double)>& done) {
  if (shadow) {
    std::vector<uint16_t> lit(morton.size());
    for (size_t i = 0; i < morton.size(); ++i) {
      const auto [x, y, z] = MortonDecode(morton[i]);
      lit[i] = shadow->Shadowed({x + 0.5, y + 0.5, z + 0.5}) ? 0 : 1;
    }
    return lit;
  }
  const std::span<const Light> lights(plan.lights);
  const size_t group = (lights.size() + 19) / 20;
  std::vector<uint16_t> lit;
  for (size_t first = 0; first < lights.size(); first += group) {
    ASSIGN_OR_RETURN(const std::vector<uint16_t> part, LitSampleCounts(dag, lights.subspan(first, std::min(group, lights.size() - first))));
    if (lit.empty()) lit.assign(part.size(), 0);
    if (part.size() != lit.size()) return Internal("the shadow pass answered for different voxel counts");
    for (size_t i = 0; i < lit.size(); ++i) lit[i] = static_cast<uint16_t>(lit[i] + part[i]);
    done(static_cast<double>(first + group) / static_cast<double>(lights.size()));
  }
  return lit;
}

StatusOr<nlohmann::json> ComputeAndCommit(Store& store, const JobRecord& job) {
  const auto started = std::chrono::steady_clock::now();
  const std::string& dataset = job.dataset_id;
  const auto progress = [&](const char* stage, double percent, uint64_t voxels) {
    (void)store.UpdateJobProgress(job.id, stage, percent, 0, voxels);
  };
  ASSIGN_OR_RETURN(const std::optional<nlohmann::json> meta, store.GetDataset(dataset));
  if (!meta) return InvalidArgument("dataset " + dataset + " was deleted");
  ASSIGN_OR_RETURN(const ShadowPlan plan, PlanShadows(job.params, *meta));
  progress("load", 2, 0);
  ASSIGN_OR_RETURN(const FinestVoxels finest, LoadFinestVoxels(store, dataset, *meta));
  const uint64_t n = finest.morton.size();
  progress("shadows", 20, n);
  ASSIGN_OR_RETURN(const Svdag dag, BuildDag(finest.morton, finest.depth));
  nlohmann::json summary = plan.description;
  ASSIGN_OR_RETURN(const std::optional<ShadowDag> shadow, ShadowDagOf(dag, plan, summary));
  ASSIGN_OR_RETURN(const std::vector<uint16_t> lit,
                   LitCounts(dag, finest.morton, plan, shadow,
                             [&](double fraction) { progress("shadows", 20 + 70 * std::min(fraction, 1.0), n); }));
  if (lit.size() != n) return Internal("the shadow pass answered for " + std::to_string(lit.size()) + " of " + std::to_string(n) + " voxels");
  progress("layers", 90, n);
  const int samples = static_cast<int>(plan.lights.size());
  ASSIGN_OR_RETURN(std::vector<TileShadowLayer> layers,
                   ComputeTileLayers(finest.morton, finest.depth, lit, plan.kind, samples, finest.tile_depth));
  if (layers.size() != finest.tile_voxels.size()) {
    return Internal(std::to_string(layers.size()) + " shadow layers for " + std::to_string(finest.tile_voxels.size()) + " tiles");
  }
  std::vector<ShadowTile> tiles;
  tiles.reserve(layers.size());
  uint64_t bytes = 0;
  for (TileShadowLayer& layer : layers) {
    const auto tile = finest.tile_voxels.find(layer.key);
    if (tile == finest.tile_voxels.end() || tile->second != layer.layer.light.size()) {
      return Internal("the shadow layer of " + TileAddress(layer.key) + " does not match a stored tile");
    }
    ASSIGN_OR_RETURN(std::vector<uint8_t> encoded, EncodeShadowLayer(layer.layer));
    bytes += encoded.size();
    tiles.push_back({layer.key, tile->second, std::move(encoded)});
  }
  uint64_t dark = 0, lit_sum = 0;
  for (uint16_t c : lit) dark += c == 0, lit_sum += c;
  const std::vector<uint8_t> shadow_dag = shadow ? shadow->Serialize() : std::vector<uint8_t>{};
  if (shadow) summary["shadow_dag_file_bytes"] = shadow_dag.size();
  summary["surface_voxels"] = n;
  summary["shadowed_voxels"] = dark;  // with several samples: voxels no sample lights
  summary["mean_lit_fraction"] = static_cast<double>(lit_sum) / (static_cast<double>(n) * samples);
  summary["tiles"] = tiles.size();
  summary["bytes"] = bytes;
  summary["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  summary["created"] = Now();
  summary["job"] = job.id;
  progress("store", 97, n);
  RETURN_IF_ERROR(store.CommitShadows(job.id, dataset, summary, tiles, shadow_dag));
  return summary;
}

}  // namespace

std::string RunShadowJob(Store& store, const JobRecord& job) {
  spdlog::info("job {}: shadows of dataset {} (attempt {})", job.id, job.dataset_id, job.attempts + 1);
  const auto summary = ComputeAndCommit(store, job);
  if (!summary.ok()) return summary.status().ToString();
  spdlog::info("job {}: shadows of dataset {}: {} voxels, {} shadowed, {} layers of {} bytes, {:.2f} s", job.id,
               job.dataset_id, (*summary)["surface_voxels"].get<uint64_t>(), (*summary)["shadowed_voxels"].get<uint64_t>(),
               (*summary)["tiles"].get<uint64_t>(), (*summary)["bytes"].get<uint64_t>(), (*summary)["seconds"].get<double>());
  return "";
}

}  // namespace pointdag::server
