// A small C++ client of pointdagd's HTTP API (proto/PROTOCOL.md): one keep-alive connection,
// plain requests, streamed uploads, and FetchDataset() which walks the tile hierarchy and decodes
// the tiles of one level back into voxels.
#pragma once

#include <array>
#include <compare>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pointdag/shadow/shadow_dag.h"
#include "pointdag/shadow/shadow_layer.h"
#include "pointdag/tile/tiler.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::client {

struct Url {
  std::string host;
  uint16_t port = 80;
  std::string target = "/";  // path and query
};
// "http://HOST[:PORT]/PATH" (no TLS: put a proxy in front for that).
StatusOr<Url> ParseUrl(const std::string& url);

struct Response {
  int status = 0;
  std::map<std::string, std::string> headers;  // names in lower case
  std::string body;
  std::string Header(const std::string& lower_name) const;
};

// Bodies above it are refused (kResourceLimit) while they are read, not after.
constexpr uint64_t kDefaultMaxBodyBytes = uint64_t{1} << 30;

class Connection {
 public:
  static StatusOr<std::unique_ptr<Connection>> Open(const std::string& host, uint16_t port,
                                                    uint64_t max_body_bytes = kDefaultMaxBodyBytes);
  ~Connection();
  StatusOr<Response> Request(const std::string& method, const std::string& target,
                             const std::map<std::string, std::string>& headers = {}, const std::string& body = "");
  // POSTs a file as the body, streamed from disk.
  StatusOr<Response> Upload(const std::string& target, const std::filesystem::path& file,
                            const std::map<std::string, std::string>& headers = {});

 private:
  struct Impl;
  explicit Connection(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// ---- What a server says, parsed as untrusted input: every number is range-checked. ----

struct DatasetShape : TileGridShape {
  uint64_t points = 0;
  bool has_shadows = false;  // its "shadows" is a summary, not null: layers exist (§3.2)
};
// The members of GET /v1/datasets/{id} that FetchDataset needs (proto/PROTOCOL.md §2).
StatusOr<DatasetShape> ParseDatasetShape(std::string_view body);

struct TileAddress {
  int level = 0;
  uint32_t x = 0, y = 0, z = 0;  // each < 2^level
  auto operator<=>(const TileAddress&) const = default;
};
struct HierarchyPage {
  std::vector<TileAddress> tiles;
  std::vector<TileAddress> pages;
};
// GET /v1/datasets/{id}/hierarchy/... (§3); addresses deeper than `max_level` are refused.
StatusOr<HierarchyPage> ParseHierarchyPage(std::string_view body, int max_level);

// What a fetch may cost, whatever the server answers.
struct FetchLimits {
  uint64_t max_body_bytes = uint64_t{256} << 20;  // one JSON answer or tile
  size_t max_pages = 100000;                      // hierarchy pages walked
  size_t max_tiles = 1000000;
  uint64_t max_voxels = uint64_t{1} << 28;        // all tiles together
};

// A GET that must answer 200 (kIoError naming the target and the answer's start otherwise).
StatusOr<Response> GetOk(Connection& connection, const std::string& target);

// Every tile of the dataset at `dataset_target` (/v1/datasets/{id}) down to `max_level`, from its
// hierarchy pages (§3) walked from the root, sorted by address.
StatusOr<std::vector<TileAddress>> ListTiles(Connection& connection, const std::string& dataset_target, int max_level,
                                             const FetchLimits& limits = {});

struct FetchedLevel {
  int level = 0;
  size_t tiles = 0;
  uint64_t tile_bytes = 0;
  VoxelGrid grid;  // the level's voxels in the dataset's frame (ENU metres when georeferenced)
  std::vector<uint8_t> light;  // with shadows: each voxel's light (SHADOW_FORMAT.md §2), parallel to grid.morton
};

// GET {dataset_target}/shadows/tiles/{level}/{x}/{y}/{z} (§3.2), decoded against `tile_voxels`, the
// voxel count of the tile at that address (a layer of another size is refused).
StatusOr<ShadowLayer> FetchShadowLayer(Connection& connection, const std::string& dataset_target, const TileAddress& tile,
                                       uint64_t tile_voxels);

// GET {dataset_target}/shadows/dag (§3.2), read with ShadowDag::Deserialize (hostile bytes are a
// typed Status); a 404 (no set, or a sun-hours set without a DAG) is kIoError naming it.
StatusOr<ShadowDag> FetchShadowDag(Connection& connection, const std::string& dataset_target);

// `dataset_url`: http://HOST:PORT/v1/datasets/{id}. Level: the finest when not given. `shadows`:
// also each tile's shadow layer into `light` (kInvalidArgument when the dataset has no shadows).
StatusOr<FetchedLevel> FetchDataset(const std::string& dataset_url, std::optional<int> level,
                                    const std::function<void(size_t done, size_t total)>& progress = {},
                                    const FetchLimits& limits = {}, bool shadows = false);

}  // namespace pointdag::client
