// Issue #14 goal 6 at the scale of one tile: a scan's tiles cut exactly as `bench --versus` cuts
// them (TileDecodeRate: BuildTiles with TilingOptions{}), then every tile parsed and decoded
// (ParsePdag + DecodePdag) pass after pass. Prints the least pass time, microseconds per tile, the
// points per second goal 6 counts, and a checksum of everything decoded (to compare two builds).
//   tile_decode_bench SCAN VOXEL [PASSES] [--write DIR]
// --write keeps the tiles as DIR/NNNN.pdag, for decode_native_bench or callgrind.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "pointdag/container/pdag_file.h"
#include "pointdag/pipeline.h"
#include "pointdag/tile/tiler.h"
#include "tile_decode_time.h"

using namespace pointdag;

namespace {

// FNV-1a over decoded values: equal sums mean (with overwhelming odds) bit-identical decodes.
struct Checksum {
  uint64_t h = 1469598103934665603ull;
  void Add(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <typename T>
  void AddVector(const std::vector<T>& v) {
    Add(v.data(), v.size() * sizeof(T));
  }
};

Status Run(const std::string& scan, double voxel, int passes, const std::string& write_dir) {
  EncodeOptions options;
  options.voxel_size = voxel;
  ASSIGN_OR_RETURN(const EncodedScan encoded, EncodeScan(scan, options));
  ASSIGN_OR_RETURN(const TileSet tiles, BuildTiles(encoded.grid, ScanInfo{}, "versus", TilingOptions{}));
  uint64_t points = 0, bytes = 0;
  Checksum tile_bytes, decoded;
  for (size_t i = 0; i < tiles.tiles.size(); ++i) {
    const Tile& tile = tiles.tiles[i];
    points += tile.voxels;
    bytes += tile.bytes.size();
    tile_bytes.AddVector(tile.bytes);
    ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(tile.bytes));
    ASSIGN_OR_RETURN(const DecodedPdag d, DecodePdag(file));
    decoded.AddVector(d.grid.morton);
    decoded.AddVector(d.grid.colors);
    decoded.AddVector(d.mip_colors);
    decoded.Add(&d.grid.origin, sizeof(d.grid.origin));
    decoded.Add(&d.grid.voxel_size, sizeof(d.grid.voxel_size));
    if (!write_dir.empty()) {
      char name[32];
      std::snprintf(name, sizeof(name), "%04zu.pdag", i);
      std::filesystem::create_directories(write_dir);
      RETURN_IF_ERROR(WriteFileAtomically(std::filesystem::path(write_dir) / name, tile.bytes));
    }
  }
  ASSIGN_OR_RETURN(const double best, BestTileDecodeSeconds(tiles, passes));
  std::printf("%s @ %g: %zu tiles, %llu voxels, %llu bytes; best of %d passes %.3f ms, %.2f us/tile, %.3f Mpoints/s;"
              " tiles %016llx decoded %016llx\n",
              std::filesystem::path(scan).filename().c_str(), voxel, tiles.tiles.size(), static_cast<unsigned long long>(points),
              static_cast<unsigned long long>(bytes), passes, best * 1e3, best * 1e6 / static_cast<double>(tiles.tiles.size()),
              static_cast<double>(points) / best / 1e6, static_cast<unsigned long long>(tile_bytes.h),
              static_cast<unsigned long long>(decoded.h));
  return Status::Ok();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SCAN VOXEL [PASSES] [--write DIR]\n", argv[0]);
    return 2;
  }
  int passes = 20;
  std::string write_dir;
  for (int i = 3; i < argc; ++i) {
    if (std::string(argv[i]) == "--write" && i + 1 < argc) {
      write_dir = argv[++i];
    } else {
      passes = std::max(1, std::atoi(argv[i]));
    }
  }
  const Status s = Run(argv[1], std::atof(argv[2]), passes, write_dir);
  if (!s.ok()) {
    std::fprintf(stderr, "%s\n", s.ToString().c_str());
    return 1;
  }
  return 0;
}
