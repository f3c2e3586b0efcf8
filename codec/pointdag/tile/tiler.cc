#include "pointdag/tile/tiler.h"

#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>

#include "pointdag/voxelize/morton.h"

namespace pointdag {

uint64_t TileSet::stored_bytes() const {
  uint64_t total = 0;
  for (const Tile& t : tiles) total += t.bytes.size();
  return total;
}

VoxelGrid LevelGrid(const VoxelGrid& finest, int level, int tile_depth) {
  const int tile = std::min(tile_depth, finest.depth);
  const int coarsening = finest.depth - tile - level;
  const int shift = 3 * coarsening;
  VoxelGrid out;
  out.depth = tile + level;
  out.origin = finest.origin;
  out.voxel_size = std::ldexp(finest.voxel_size, coarsening);
  out.points_in = finest.points_in;
  out.source_color_bits = finest.source_color_bits;
  for (size_t i = 0; i < finest.morton.size();) {
    const uint64_t code = finest.morton[i] >> shift;
    std::array<uint64_t, 3> sum{0, 0, 0};
    size_t j = i;
    for (; j < finest.morton.size() && (finest.morton[j] >> shift) == code; ++j) {
      if (finest.has_color()) {
        sum[0] += finest.colors[j].r;
        sum[1] += finest.colors[j].g;
        sum[2] += finest.colors[j].b;
      }
    }
    out.morton.push_back(code);
    if (finest.has_color()) {
      const uint64_t n = j - i;
      const auto mean = [n](uint64_t s) { return static_cast<uint8_t>((s + n / 2) / n); };
      out.colors.push_back({mean(sum[0]), mean(sum[1]), mean(sum[2])});
    }
    i = j;
  }
  return out;
}

StatusOr<TileSet> BuildTiles(const VoxelGrid& finest, const ScanInfo& scan, const std::string& source_name,
                             const TilingOptions& options) {
  if (finest.morton.empty()) return InvalidArgument("no voxels to tile");
  TileSet set;
  set.tile_depth = std::min(options.tile_depth, finest.depth);
  set.levels = finest.depth - set.tile_depth + 1;
  const int local_bits = 3 * set.tile_depth;
  const uint64_t local_mask = (uint64_t{1} << local_bits) - 1;

  struct Pending {
    TileKey key;
    const VoxelGrid* level;
    size_t first, end;
  };
  // The coarser levels averaged from the finest voxels; the finest level is `finest` itself, not a copy.
  std::vector<VoxelGrid> coarser;
  coarser.reserve(static_cast<size_t>(set.levels - 1));
  std::vector<Pending> pending;
  for (int l = 0; l < set.levels; ++l) {
    const VoxelGrid& grid = l + 1 < set.levels ? coarser.emplace_back(LevelGrid(finest, l, set.tile_depth)) : finest;
    for (size_t i = 0; i < grid.morton.size();) {
      const uint64_t tile_code = grid.morton[i] >> local_bits;
      size_t j = i;
      while (j < grid.morton.size() && (grid.morton[j] >> local_bits) == tile_code) ++j;
      const auto [x, y, z] = MortonDecode(tile_code);
      pending.push_back({{l, x, y, z}, &grid, i, j});
      i = j;
    }
  }

  EncodeOptions encode;
  encode.geometry_coder = options.geometry_coder;
  encode.geometry_version = options.geometry_version;
  encode.colors = options.colors;
  encode.mipmap = true;
  set.tiles.resize(pending.size());
  std::vector<Status> failures(pending.size());
  std::atomic<uint64_t> done{0};
  // The largest tile of each level goes first; the threshold its colors' target settled on is where
  // the level's other tiles start (the same scan at the same scale: no sample to predict one). A
  // level's other tiles start as soon as its lead is done, not when every level's lead is: the cores
  // do not idle behind the finest level's lead (the hints, hence the bytes, are the same).
  std::vector<size_t> leads;
  std::vector<std::vector<size_t>> rest(static_cast<size_t>(set.levels));
  const auto size = [&](size_t k) { return pending[k].end - pending[k].first; };
  for (size_t t = 0; t < pending.size(); ++t) {
    const bool new_level = leads.empty() || pending[leads.back()].key.level != pending[t].key.level;
    auto& others = rest[static_cast<size_t>(pending[t].key.level)];
    if (new_level) {
      leads.push_back(t);
    } else if (size(t) > size(leads.back())) {
      others.push_back(leads.back());
      leads.back() = t;
    } else {
      others.push_back(t);
    }
  }
  // Spawned smallest first: a thread runs its own tasks last in, first out, so the largest start
  // early, while idle threads steal the oldest (smallest) ones: the cores meet near the end.
  const auto smaller = [&](size_t a, size_t b) { return size(a) != size(b) ? size(a) < size(b) : a > b; };
  std::sort(leads.begin(), leads.end(), smaller);
  for (auto& others : rest) std::sort(others.begin(), others.end(), smaller);
  std::vector<std::optional<double>> encoded_hint(pending.size());
  const auto encode_tile = [&](size_t t, std::optional<double> hint) {
    const Pending& p = pending[t];
    VoxelGrid grid;
    grid.depth = set.tile_depth;
    grid.voxel_size = p.level->voxel_size;
    const double span = std::ldexp(grid.voxel_size, set.tile_depth);
    grid.origin = {finest.origin[0] + p.key.x * span, finest.origin[1] + p.key.y * span, finest.origin[2] + p.key.z * span};
    grid.points_in = finest.points_in;
    grid.source_color_bits = finest.source_color_bits;
    grid.morton.reserve(p.end - p.first);
    for (size_t i = p.first; i < p.end; ++i) grid.morton.push_back(p.level->morton[i] & local_mask);
    if (p.level->has_color()) grid.colors.assign(p.level->colors.begin() + static_cast<long>(p.first), p.level->colors.begin() + static_cast<long>(p.end));
    EncodeOptions tile_options = encode;
    tile_options.colors.threshold_hint = hint;
    auto encoded = EncodeGrid(std::move(grid), scan, source_name, tile_options);
    if (!encoded.ok()) {
      failures[t] = encoded.status();
      return;
    }
    if (encoded->colors.max_mse > 0) encoded_hint[t] = encoded->colors.max_mse;
    // A tile's metadata is what placing and decoding it needs; the scan's (source, CRS, bounds) is
    // the dataset description's, said once: in every tile it was a third of a small tile's bytes
    // and a sixth of its decode (docs/benchmarks.md, "Tiles store the voxels' colors only").
    for (const char* scan_wide : {"source", "crs", "grid_bounds"}) encoded->file.meta.erase(scan_wide);
    encoded->file.meta["tile"] = {{"level", p.key.level}, {"x", p.key.x}, {"y", p.key.y}, {"z", p.key.z}};
    set.tiles[t] = {p.key, p.end - p.first, SerializePdag(encoded->file)};
    const uint64_t finished = ++done;
    if (options.progress) options.progress(finished, pending.size());
  };
  tbb::task_group group;
  for (size_t lead : leads) {
    group.run([&, lead] {
      encode_tile(lead, std::nullopt);
      for (size_t t : rest[static_cast<size_t>(pending[lead].key.level)]) {
        group.run([&, t, hint = encoded_hint[lead]] { encode_tile(t, hint); });
      }
    });
  }
  group.wait();
  for (const Status& s : failures) RETURN_IF_ERROR(s);
  return set;
}

StatusOr<TileGridShape> ReadTileGridShape(const JsonFields& description) {
  TileGridShape out;
  ASSIGN_OR_RETURN(const int64_t tile_depth, description.Int("tile_depth", 2, 8));
  ASSIGN_OR_RETURN(const int64_t levels, description.Int("levels", 1, kMaxDepth - tile_depth + 1));
  out.tile_depth = static_cast<int>(tile_depth);
  out.levels = static_cast<int>(levels);
  ASSIGN_OR_RETURN(out.origin, description.Vec3("bounds/min"));
  ASSIGN_OR_RETURN(out.voxel_size, description.Number("voxel_size"));
  if (!(out.voxel_size > 0)) return Malformed("the dataset description's 'voxel_size' is not positive");
  return out;
}

}  // namespace pointdag
