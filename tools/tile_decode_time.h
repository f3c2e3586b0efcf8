// Goal 6's clock (issue #14): every tile of a set parsed and decoded as a client does (ParsePdag,
// DecodePdag), the least time of `passes` passes. `bench --versus` (TileDecodeRate) and
// tile_decode_bench time the same loop.
#pragma once

#include <chrono>

#include "pointdag/container/pdag_file.h"
#include "pointdag/pipeline.h"
#include "pointdag/tile/tiler.h"

namespace pointdag {

inline StatusOr<double> BestTileDecodeSeconds(const TileSet& tiles, int passes) {
  double best = 0;
  for (int pass = 0; pass < passes; ++pass) {
    const auto start = std::chrono::steady_clock::now();
    for (const Tile& tile : tiles.tiles) {
      ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(tile.bytes));
      RETURN_IF_ERROR(DecodePdag(file).status());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (pass == 0 || seconds < best) best = seconds;
  }
  return best;
}

}  // namespace pointdag
