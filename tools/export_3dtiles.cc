#include "export_3dtiles.h"

#include <chrono>
#include <utility>
#include <vector>

#include "pointdag/container/json_fields.h"
#include "pointdag/ingest.h"
#include "pointdag/json_text.h"
#include "pointdag/tiles3d/tile_content.h"

namespace pointdag {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Transcodes and writes the tiles one by one, keeping their boxes for the tileset written last.
class TilesetWriter {
 public:
  TilesetWriter(std::filesystem::path dir, TilesetDataset dataset) : dir_(std::move(dir)), dataset_(std::move(dataset)) {}

  Status Add(const TileKey& key, std::span<const uint8_t> pdag) {
    const std::string uri = ContentUri(key);
    const auto started = Clock::now();
    auto content = TranscodeTile(key, pdag, dataset_.tile_depth);
    if (!content.ok()) return Status(content.status().code(), "tile " + uri + ": " + content.status().message());
    report_.transcode_seconds += Since(started);
    const std::filesystem::path path = dir_ / uri;
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    if (ec) return IoError("cannot create " + path.parent_path().string() + ": " + ec.message());
    RETURN_IF_ERROR(WriteFileAtomically(path, content->glb));
    boxes_.push_back(content->box);
    ++report_.tiles;
    report_.pdag_bytes += pdag.size();
    report_.glb_bytes += content->glb.size();
    return Status();
  }

  StatusOr<ExportReport> Finish(Clock::time_point started) {
    ASSIGN_OR_RETURN(const std::string tileset, BuildTileset(dataset_, std::move(boxes_)));
    const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(tileset.data()), tileset.size());
    RETURN_IF_ERROR(WriteFileAtomically(dir_ / "tileset.json", bytes));
    report_.tileset_bytes = tileset.size();
    report_.seconds = Since(started);
    return report_;
  }

 private:
  std::filesystem::path dir_;
  TilesetDataset dataset_;
  std::vector<TileBox> boxes_;
  ExportReport report_;
};

}  // namespace

StatusOr<ExportReport> ExportTiles3dFromUrl(const std::string& dataset_url, const std::filesystem::path& dir,
                                            const client::FetchLimits& limits) {
  const auto started = Clock::now();
  ASSIGN_OR_RETURN(const client::Url url, client::ParseUrl(dataset_url));
  ASSIGN_OR_RETURN(std::unique_ptr<client::Connection> connection,
                   client::Connection::Open(url.host, url.port, limits.max_body_bytes));
  ASSIGN_OR_RETURN(const client::Response described, client::GetOk(*connection, url.target));
  ASSIGN_OR_RETURN(const nlohmann::json description, ParseJson(described.body));
  ASSIGN_OR_RETURN(TilesetDataset dataset, ParseTilesetDataset(description));
  ASSIGN_OR_RETURN(const std::vector<client::TileAddress> tiles,
                   client::ListTiles(*connection, url.target, dataset.levels - 1, limits));
  TilesetWriter writer(dir, std::move(dataset));
  for (const client::TileAddress& t : tiles) {
    const TileKey key{t.level, t.x, t.y, t.z};
    ASSIGN_OR_RETURN(const client::Response tile,
                     client::GetOk(*connection, url.target + "/tiles/" + std::to_string(t.level) + "/" + std::to_string(t.x) +
                                                    "/" + std::to_string(t.y) + "/" + std::to_string(t.z)));
    RETURN_IF_ERROR(writer.Add(key, {reinterpret_cast<const uint8_t*>(tile.body.data()), tile.body.size()}));
  }
  return writer.Finish(started);
}

StatusOr<ExportReport> ExportTiles3dFromPdag(const std::filesystem::path& pdag, const std::filesystem::path& dir) {
  const auto started = Clock::now();
  ASSIGN_OR_RETURN(const PdagFile file, ReadPdag(pdag));
  ASSIGN_OR_RETURN(const DecodedPdag decoded, DecodePdag(file));
  const TilingOptions tiling = IngestTilingOptions(IngestOptions{}.tile_depth, std::nullopt);
  ASSIGN_OR_RETURN(const TileSet tiles, BuildTiles(decoded.grid, ScanInfo{}, pdag.filename().string(), tiling));
  // The description pointdagd would give, with the file's own frame.
  const nlohmann::json* frame = JsonFields(file.meta, ".pdag metadata").Find("frame");
  const nlohmann::json description = {
      {"bounds", {{"min", decoded.grid.origin}}},
      {"voxel_size", decoded.grid.voxel_size},
      {"levels", tiles.levels},
      {"tile_depth", tiles.tile_depth},
      {"frame", frame ? *frame : nlohmann::json{{"georeferenced", false}}},
  };
  ASSIGN_OR_RETURN(TilesetDataset dataset, ParseTilesetDataset(description));
  TilesetWriter writer(dir, std::move(dataset));
  for (const Tile& t : tiles.tiles) RETURN_IF_ERROR(writer.Add(t.key, t.bytes));
  return writer.Finish(started);
}

}  // namespace pointdag
