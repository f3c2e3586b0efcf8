#include "tile_cache.h"

namespace pointdag::server {

std::shared_ptr<const StoredTile> TileCache::Get(const std::string& key) {
  std::lock_guard lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end()) return nullptr;
  order_.splice(order_.begin(), order_, it->second);
  return it->second->second;
}

uint64_t TileCache::generation() const {
  std::lock_guard lock(mutex_);
  return generation_;
}

void TileCache::Put(const std::string& key, std::shared_ptr<const StoredTile> tile, uint64_t read_generation) {
  std::lock_guard lock(mutex_);
  if (read_generation != generation_ || index_.count(key) || tile->bytes.size() > capacity_) return;
  size_ += tile->bytes.size();
  order_.emplace_front(key, std::move(tile));
  index_[key] = order_.begin();
  while (size_ > capacity_) {
    size_ -= order_.back().second->bytes.size();
    index_.erase(order_.back().first);
    order_.pop_back();
  }
}

void TileCache::EraseDataset(const std::string& dataset_id) {
  std::lock_guard lock(mutex_);
  ++generation_;
  for (auto it = order_.begin(); it != order_.end();) {
    if (it->first.rfind(dataset_id + "/", 0) == 0) {
      size_ -= it->second->bytes.size();
      index_.erase(it->first);
      it = order_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace pointdag::server
