#include "shadow_query.h"

#include <charconv>
#include <cmath>

#include "pointdag/dag/dag_builder.h"
#include "shadow_job.h"

namespace pointdag::server {
namespace {

StatusOr<double> Coordinate(const std::map<std::string, std::string>& query, const char* name) {
  const auto it = query.find(name);
  if (it == query.end() || it->second.empty()) {
    return InvalidArgument(std::string("give the point as ?x=&y=&z= in the dataset's frame; ") + name + " is missing");
  }
  const std::string& text = it->second;
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    return InvalidArgument(std::string(name) + "=" + text.substr(0, 32) + " is not a finite number");
  }
  return value;
}

}  // namespace

StatusOr<std::shared_ptr<const QueryableShadows>> ShadowQueryCache::Load(const std::string& dataset) {
  ASSIGN_OR_RETURN(const std::optional<StoredTile> stored, store_.GetShadowDag(dataset));
  if (!stored) return std::shared_ptr<const QueryableShadows>();
  if (TileEtag(stored->bytes) != stored->etag) {
    return Corrupt("the shadow DAG of dataset " + dataset + " does not match its checksum; run pointdagd --check");
  }
  auto out = std::make_shared<QueryableShadows>();
  out->etag = stored->etag;
  auto dag = ShadowDag::Deserialize(stored->bytes);
  if (!dag.ok()) return Corrupt("the shadow DAG of dataset " + dataset + " does not read: " + dag.status().ToString());
  out->dag = std::move(*dag);
  ASSIGN_OR_RETURN(const std::optional<nlohmann::json> meta, store_.GetDataset(dataset));
  if (!meta) return std::shared_ptr<const QueryableShadows>();  // deleted meanwhile
  const nlohmann::json min = meta->value("bounds", nlohmann::json::object()).value("min", nlohmann::json());
  const nlohmann::json size = meta->value("voxel_size", nlohmann::json());
  if (!min.is_array() || min.size() != 3 || !size.is_number() || !(size.get<double>() > 0)) {
    return Corrupt("the metadata of dataset " + dataset + " lacks its grid (bounds.min, voxel_size)");
  }
  for (int a = 0; a < 3; ++a) {
    if (!min[a].is_number()) return Corrupt("the metadata of dataset " + dataset + " has a bad bounds.min");
    out->origin[a] = min[a].get<double>();
  }
  out->voxel_size = size.get<double>();
  ASSIGN_OR_RETURN(const FinestVoxels finest, LoadFinestVoxels(store_, dataset, *meta));
  ASSIGN_OR_RETURN(out->voxels, BuildDag(finest.morton, finest.depth));
  return std::shared_ptr<const QueryableShadows>(std::move(out));
}

StatusOr<std::shared_ptr<const QueryableShadows>> ShadowQueryCache::Get(const std::string& dataset) {
  ASSIGN_OR_RETURN(const std::optional<std::string> etag, store_.GetShadowDagEtag(dataset));
  {
    std::lock_guard lock(mutex_);
    const auto it = entries_.find(dataset);
    if (etag && it != entries_.end() && it->second->etag == *etag) return it->second;
    entries_.erase(dataset);  // replaced or gone
  }
  if (!etag) return std::shared_ptr<const QueryableShadows>();
  ASSIGN_OR_RETURN(std::shared_ptr<const QueryableShadows> loaded, Load(dataset));
  std::lock_guard lock(mutex_);
  if (loaded) entries_[dataset] = loaded;
  return loaded;
}

void ShadowQueryCache::Erase(const std::string& dataset) {
  std::lock_guard lock(mutex_);
  entries_.erase(dataset);
}

StatusOr<nlohmann::json> AnswerShadowQuery(const QueryableShadows& shadows, const std::map<std::string, std::string>& query) {
  std::array<double, 3> point{};
  ASSIGN_OR_RETURN(point[0], Coordinate(query, "x"));
  ASSIGN_OR_RETURN(point[1], Coordinate(query, "y"));
  ASSIGN_OR_RETURN(point[2], Coordinate(query, "z"));
  const double side = std::ldexp(1.0, shadows.voxels.depth);  // voxels per side
  std::array<uint32_t, 3> voxel{};
  std::array<double, 3> centre{}, grid_centre{};
  for (int a = 0; a < 3; ++a) {
    const double g = (point[a] - shadows.origin[a]) / shadows.voxel_size;
    if (!(g >= 0 && g <= side)) {
      return InvalidArgument("the point is outside the dataset's grid: each coordinate from bounds.min to bounds.max (" +
                             std::string(1, static_cast<char>('x' + a)) + " from " + std::to_string(shadows.origin[a]) +
                             " to " + std::to_string(shadows.origin[a] + side * shadows.voxel_size) + ")");
    }
    voxel[a] = static_cast<uint32_t>(std::min(std::floor(g), side - 1));  // the top face belongs to the last cell
    grid_centre[a] = voxel[a] + 0.5;
    centre[a] = shadows.origin[a] + grid_centre[a] * shadows.voxel_size;
  }
  return nlohmann::json{{"shadowed", shadows.dag.Shadowed(grid_centre)},
                        {"exact", shadows.voxels.Contains(voxel[0], voxel[1], voxel[2])},
                        {"voxel", voxel},
                        {"centre", centre}};
}

}  // namespace pointdag::server
