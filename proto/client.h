// A small C++ client of pointdagd's HTTP API (proto/PROTOCOL.md): one keep-alive connection,
// plain requests, streamed uploads, and FetchDataset() which walks the tile hierarchy and decodes
// the tiles of one level back into voxels.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>

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

class Connection {
 public:
  static StatusOr<std::unique_ptr<Connection>> Open(const std::string& host, uint16_t port);
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

struct FetchedLevel {
  int level = 0;
  size_t tiles = 0;
  uint64_t tile_bytes = 0;
  VoxelGrid grid;  // the level's voxels in the dataset's frame (ENU metres when georeferenced)
};

// `dataset_url`: http://HOST:PORT/v1/datasets/{id}. Level: the finest when not given.
StatusOr<FetchedLevel> FetchDataset(const std::string& dataset_url, std::optional<int> level,
                                    const std::function<void(size_t done, size_t total)>& progress = {});

}  // namespace pointdag::client
