// Immutable tiles recently served, least recently used dropped first.
//
// Contract: a tile read from the store before a dataset was erased is never put back afterwards.
// Readers take generation() before their store read and pass it to Put(), which refuses the tile
// when an EraseDataset() happened in between (a GET missing the cache just before a DELETE).
#pragma once

#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <utility>

#include "store.h"

namespace pointdag::server {

class TileCache {
 public:
  explicit TileCache(size_t capacity_bytes) : capacity_(capacity_bytes) {}
  std::shared_ptr<const StoredTile> Get(const std::string& key);
  uint64_t generation() const;
  void Put(const std::string& key, std::shared_ptr<const StoredTile> tile, uint64_t read_generation);
  // Keys are "<dataset id>/level/x/y/z".
  void EraseDataset(const std::string& dataset_id);

 private:
  using Entry = std::pair<std::string, std::shared_ptr<const StoredTile>>;
  mutable std::mutex mutex_;
  size_t capacity_, size_ = 0;
  uint64_t generation_ = 0;  // erasures so far
  std::list<Entry> order_;   // most recent first
  std::unordered_map<std::string, std::list<Entry>::iterator> index_;
};

}  // namespace pointdag::server
