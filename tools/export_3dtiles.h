// pointdag export IN.pdag|URL --3dtiles DIR: a dataset as 3D Tiles 1.1 static files,
// DIR/tileset.json and DIR/{level}/{x}/{y}/{z}.glb (codec/pointdag/tiles3d/).
//
// Contract:
//   From http://HOST:PORT/v1/datasets/{id}: the dataset's description, its hierarchy pages and
//     every stored tile, transcoded here: byte for byte what pointdagd serves under .../3dtiles/.
//   From a .pdag file (a whole scan): decoded, cut into LOD tiles as pointdagd cuts an upload
//     (IngestTilingOptions: tile depth 8, VBR colors at 38 dB), then transcoded the same way. The
//     frame is the file's own: ENU->ECEF from `encode --georeference`, else none (identity).
// Every file is written atomically; DIR is created when missing. Errors: the stages' Status.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "client.h"

namespace pointdag {

struct ExportReport {
  size_t tiles = 0;
  uint64_t pdag_bytes = 0;     // the LOD tiles transcoded
  uint64_t glb_bytes = 0;      // all .glb written
  uint64_t tileset_bytes = 0;
  double transcode_seconds = 0;  // decoding the tiles and writing glTF (files excluded)
  double seconds = 0;            // the whole export
};

StatusOr<ExportReport> ExportTiles3dFromUrl(const std::string& dataset_url, const std::filesystem::path& dir,
                                            const client::FetchLimits& limits = {});
StatusOr<ExportReport> ExportTiles3dFromPdag(const std::filesystem::path& pdag, const std::filesystem::path& dir);

}  // namespace pointdag
