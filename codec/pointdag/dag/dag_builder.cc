#include "pointdag/dag/dag_builder.h"

#include <xxhash.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <string>
#include <vector>

#include "pointdag/gpu/dag_hashes.h"
#include "pointdag/gpu/stage_device.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

constexpr uint32_t kNoId = ~uint32_t{0};

// Unique subtrees of one height (2 = bricks, 3.. = internal nodes), found by hash + confirmation.
struct UniqueLevel {
  std::vector<uint64_t> hash;
  std::vector<uint64_t> count;
  std::vector<uint64_t> brick;        // height 2 only: the 4x4x4 mask
  std::vector<uint8_t> mask;          // height >= 3: child mask
  std::vector<uint32_t> first_child;  // height >= 3: index into `children`
  std::vector<uint32_t> children;     // ids on height - 1, in octant order
  std::vector<uint32_t> slots;        // open addressing: id + 1, 0 = empty

  size_t size() const { return hash.size(); }
};

}  // namespace

class DagMerger::Impl {
 public:
  Impl(int depth, const DagBuildOptions& options) : depth_(depth), options_(options), levels_(depth + 1) {}

  // Hashes computed elsewhere (the Vulkan kernels), per height in Morton order: the streaming pass
  // interns each height's cells in that order, so it takes them one by one instead of hashing.
  void UseHashes(std::vector<std::vector<uint64_t>> hashes) {
    given_ = std::move(hashes);
    use_given_ = true;
  }

  uint32_t InternBrick(uint64_t brick) {
    UniqueLevel& level = levels_[2];
    const uint64_t h = (use_given_ ? Given(2) : XXH3_64bits(&brick, sizeof(brick))) & options_.hash_mask;
    return Intern(level, h, [&](uint32_t id) { return level.brick[id] == brick; }, [&] {
      level.brick.push_back(brick);
      level.count.push_back(options_.mode == CountMode::kMipmap ? BrickMipCount(brick) : BrickVoxelCount(brick));
    });
  }

  uint32_t InternNode(int height, uint8_t mask, const uint32_t* child_ids) {
    UniqueLevel& level = levels_[height];
    const UniqueLevel& below = levels_[height - 1];
    const int n = __builtin_popcount(mask);
    // Paper I: a node's hash comes from its mask and its children's hashes, not their ids, so the
    // same subtree hashes alike in every sub-DAG.
    std::array<uint64_t, 9> key{};
    key[0] = mask;
    uint64_t count = options_.mode == CountMode::kMipmap ? 1 : 0;
    for (int i = 0; i < n; ++i) {
      key[1 + i] = below.hash[child_ids[i]];
      count += below.count[child_ids[i]];
    }
    const uint64_t h = (use_given_ ? Given(height) : XXH3_64bits(key.data(), sizeof(uint64_t) * (1 + n))) & options_.hash_mask;
    return Intern(
        level, h,
        [&](uint32_t id) {
          if (level.mask[id] != mask) return false;
          const uint32_t* other = &level.children[level.first_child[id]];
          for (int i = 0; i < n; ++i) {
            if (other[i] != child_ids[i]) return false;
          }
          return true;
        },
        [&] {
          level.mask.push_back(mask);
          level.first_child.push_back(static_cast<uint32_t>(level.children.size()));
          level.children.insert(level.children.end(), child_ids, child_ids + n);
          level.count.push_back(count);
        });
  }

  // Streaming construction: subtree `id` of `height` covers the cell `key` (Morton code at that
  // height). Cells must arrive in increasing key order.
  Status Push(int height, uint64_t key, uint32_t id) {
    if (height == depth_) {
      if (root_ != kNoId) return Internal("two roots pushed into one DAG");
      root_ = id;
      return Status::Ok();
    }
    const int parent = height + 1;
    Pending& p = pending_[parent];
    const uint64_t parent_key = key >> 3;
    const uint32_t octant = static_cast<uint32_t>(key & 7);
    if (p.mask != 0 && p.key != parent_key) RETURN_IF_ERROR(Flush(parent));
    if (p.mask == 0) p.key = parent_key;
    if (p.mask >> octant) return InvalidArgument("voxels are not sorted by strictly increasing Morton code");
    p.children[__builtin_popcount(p.mask)] = id;
    p.mask = static_cast<uint8_t>(p.mask | (1u << octant));
    return Status::Ok();
  }

  Status Finish() {
    for (int height = 3; height <= depth_; ++height) {
      if (pending_[height].mask != 0) RETURN_IF_ERROR(Flush(height));
    }
    if (root_ == kNoId) return InvalidArgument("a DAG needs at least one voxel");
    for (int height = 2; use_given_ && height <= depth_; ++height) {
      if (given_next_[height] != given_[height].size()) return Internal("the given subtree hashes do not match the DAG's cells");
    }
    return Status::Ok();
  }

  // Interns every node of `sub` bottom-up and joins its root to the streaming pass.
  Status AddSubdag(const Svdag& sub, uint64_t prefix) {
    if (sub.mode != options_.mode) return InvalidArgument("sub-DAGs of different count modes cannot be merged");
    if (sub.depth > depth_) return InvalidArgument("a sub-DAG is deeper than the DAG it merges into");
    std::vector<uint32_t> leaf_ids(sub.leaves.size());
    for (size_t i = 0; i < sub.leaves.size(); ++i) leaf_ids[i] = InternBrick(sub.leaves[i]);
    std::vector<uint32_t> word_ids(sub.nodes.size(), kNoId);
    for (int level = sub.internal_levels() - 1; level >= 0; --level) {
      const bool children_are_leaves = level == sub.internal_levels() - 1;
      for (size_t w = sub.level_offsets[level]; w < sub.level_offsets[level + 1];) {
        const uint8_t mask = sub.Mask(static_cast<uint32_t>(w));
        const int n = __builtin_popcount(mask);
        uint32_t ids[8];
        for (int i = 0; i < n; ++i) {
          const uint32_t ref = sub.nodes[w + 1 + i];
          ids[i] = children_are_leaves ? leaf_ids[ref] : word_ids[ref];
        }
        word_ids[w] = InternNode(sub.depth - level, mask, ids);
        w += 1 + static_cast<size_t>(n);
      }
    }
    return Push(sub.depth, prefix, sub.internal_levels() == 0 ? leaf_ids[0] : word_ids[0]);
  }

  // Top-down pass: unique nodes, breadth-first from the root, numbered in first-seen order.
  StatusOr<Svdag> Emit() const {
    Svdag dag;
    dag.depth = depth_;
    dag.mode = options_.mode;
    std::vector<uint32_t> order{root_};  // ids on the current height, in output order
    for (int level = 0; level < depth_ - 2; ++level) {
      const int height = depth_ - level;
      const UniqueLevel& here = levels_[height];
      const UniqueLevel& below = levels_[height - 1];
      dag.level_offsets.push_back(static_cast<uint32_t>(dag.nodes.size()));
      size_t level_words = 0;
      for (uint32_t id : order) level_words += 1 + static_cast<size_t>(__builtin_popcount(here.mask[id]));
      if (dag.nodes.size() + level_words > 0xFFFFFFFFull) return ResourceLimit("DAG exceeds 2^32 node words");
      // Word address of each next-level node, assigned when first referenced.
      std::vector<uint32_t> address(below.size(), kNoId);
      std::vector<uint32_t> next_order;
      uint64_t next_address = dag.nodes.size() + level_words;
      const bool children_are_leaves = height - 1 == 2;
      for (uint32_t id : order) {
        const uint64_t count = here.count[id];
        uint32_t field;
        if (dag.IsUpperLevel(level)) {
          if (count > 0xFFFFFFFFull) return ResourceLimit("more than 2^32 voxels in one DAG");
          if (dag.upper_counts.size() >= 0xFFFFFFu) return ResourceLimit("too many nodes on the upper DAG levels");
          field = static_cast<uint32_t>(dag.upper_counts.size());
          dag.upper_counts.push_back(static_cast<uint32_t>(count));
        } else {
          if (count >= 0xFFFFFFu) return Internal("24-bit count overflow below the upper levels");
          field = static_cast<uint32_t>(count);
        }
        dag.nodes.push_back(uint32_t{here.mask[id]} << 24 | field);
        const int n = __builtin_popcount(here.mask[id]);
        for (int i = 0; i < n; ++i) {
          const uint32_t child = here.children[here.first_child[id] + i];
          if (address[child] == kNoId) {
            if (children_are_leaves) {
              address[child] = static_cast<uint32_t>(dag.leaves.size());
              dag.leaves.push_back(below.brick[child]);
            } else {
              address[child] = static_cast<uint32_t>(next_address);
              next_address += 1 + static_cast<uint64_t>(__builtin_popcount(below.mask[child]));
              next_order.push_back(child);
            }
          }
          dag.nodes.push_back(address[child]);
        }
      }
      order.swap(next_order);
    }
    if (depth_ == 2) dag.leaves.push_back(levels_[2].brick[root_]);
    if (depth_ > 2) dag.level_offsets.push_back(static_cast<uint32_t>(dag.nodes.size()));
    return dag;
  }

 private:
  struct Pending {
    uint64_t key = 0;
    uint8_t mask = 0;
    std::array<uint32_t, 8> children{};
  };

  Status Flush(int height) {
    Pending& p = pending_[height];
    const uint32_t id = InternNode(height, p.mask, p.children.data());
    const uint64_t key = p.key;
    p.mask = 0;
    return Push(height, key, id);
  }

  template <typename Equal, typename Append>
  uint32_t Intern(UniqueLevel& level, uint64_t h, Equal&& equal, Append&& append) {
    if (level.size() * 2 >= level.slots.size()) Grow(level);
    const size_t mask = level.slots.size() - 1;
    for (size_t i = Slot(h, mask);; i = (i + 1) & mask) {
      const uint32_t entry = level.slots[i];
      if (entry == 0) {
        const uint32_t id = static_cast<uint32_t>(level.size());
        level.hash.push_back(h);
        append();
        level.slots[i] = id + 1;
        return id;
      }
      if (level.hash[entry - 1] == h && equal(entry - 1)) return entry - 1;
    }
  }

  uint64_t Given(int height) {
    const auto& level = given_[height];
    const size_t next = given_next_[height]++;
    return next < level.size() ? level[next] : 0;  // a shortfall fails Finish()
  }

  static size_t Slot(uint64_t h, size_t mask) { return static_cast<size_t>((h * 0x9E3779B97F4A7C15ull) >> 20) & mask; }

  static void Grow(UniqueLevel& level) {
    const size_t capacity = std::max<size_t>(64, level.slots.size() * 2);
    level.slots.assign(capacity, 0);
    const size_t mask = capacity - 1;
    for (uint32_t id = 0; id < level.size(); ++id) {
      size_t i = Slot(level.hash[id], mask);
      while (level.slots[i] != 0) i = (i + 1) & mask;
      level.slots[i] = id + 1;
    }
  }

  int depth_;
  DagBuildOptions options_;
  std::vector<UniqueLevel> levels_;  // indexed by height
  std::array<Pending, kMaxDepth + 1> pending_;
  uint32_t root_ = kNoId;
  std::vector<std::vector<uint64_t>> given_;
  bool use_given_ = false;
  std::array<size_t, kMaxDepth + 1> given_next_{};
};

namespace {

// The kernels hash with every bit kept; a narrowed hash (tests) stays on the CPU.
StatusOr<gpu::VulkanContext*> DeviceForHashes(const DagBuildOptions& options) {
  if (options.hash_mask != ~uint64_t{0}) return nullptr;
  return DagHashesDevice();
}

Status CheckDepth(int depth) {
  if (depth < 2 || depth > kMaxDepth) return InvalidArgument("DAG depth must be 2..21, got " + std::to_string(depth));
  return Status::Ok();
}

// Feeds sorted codes (all below 8^depth) to the interner, one brick at a time.
Status PushVoxels(DagMerger::Impl& interner, std::span<const uint64_t> morton, int depth) {
  const uint64_t limit = uint64_t{1} << (3 * depth);
  for (size_t i = 0; i < morton.size();) {
    const uint64_t brick_key = morton[i] >> 6;
    uint64_t brick = 0;
    for (; i < morton.size() && morton[i] >> 6 == brick_key; ++i) {
      if (morton[i] >= limit) return InvalidArgument("Morton code outside the depth-" + std::to_string(depth) + " grid");
      if (i > 0 && morton[i] <= morton[i - 1]) {
        return InvalidArgument("voxels are not sorted by strictly increasing Morton code");
      }
      brick |= uint64_t{1} << (morton[i] & 63);
    }
    RETURN_IF_ERROR(interner.Push(2, brick_key, interner.InternBrick(brick)));
  }
  return Status::Ok();
}

}  // namespace

DagMerger::DagMerger(int depth, int chunk_levels, const DagBuildOptions& options)
    : impl_(std::make_unique<Impl>(depth, options)), depth_(depth), chunk_levels_(chunk_levels), options_(options) {}
DagMerger::~DagMerger() = default;
DagMerger::DagMerger(DagMerger&&) noexcept = default;

StatusOr<DagMerger> DagMerger::Create(int depth, int chunk_levels, const DagBuildOptions& options) {
  RETURN_IF_ERROR(CheckDepth(depth));
  if (chunk_levels < 0 || depth - chunk_levels < 2) {
    return InvalidArgument("chunk levels must leave sub-DAGs of depth 2 or more");
  }
  return DagMerger(depth, chunk_levels, options);
}

Status DagMerger::AddSubdag(const Svdag& sub, uint64_t prefix) {
  if (sub.depth != depth_ - chunk_levels_) return InvalidArgument("sub-DAG depth does not match the chunk size");
  if (prefix >> (3 * chunk_levels_) != 0) return InvalidArgument("sub-DAG prefix lies outside the grid");
  if (added_any_ && prefix <= last_prefix_) return InvalidArgument("sub-DAGs must come in strictly increasing prefix order");
  added_any_ = true;
  last_prefix_ = prefix;
  return impl_->AddSubdag(sub, prefix);
}

Status DagMerger::AddChunk(std::span<const uint64_t> codes) {
  if (codes.empty()) return Status::Ok();
  if (chunk_levels_ == 0) {  // one chunk is the whole grid: stream it in, no sub-DAG to intern twice
    if (added_any_) return InvalidArgument("a grid of one chunk takes one chunk");
    added_any_ = true;
    ASSIGN_OR_RETURN(gpu::VulkanContext* const device, DeviceForHashes(options_));
    if (device) {
      if (codes.back() >> (3 * depth_) != 0) return InvalidArgument("Morton code outside the depth-" + std::to_string(depth_) + " grid");
      ASSIGN_OR_RETURN(gpu::DagLevelHashes hashes, gpu::HashDagLevels(*device, codes, depth_));
      impl_->UseHashes(std::move(hashes.hashes));
    }
    return PushVoxels(*impl_, codes, depth_);
  }
  const int sub_depth = depth_ - chunk_levels_;
  const int shift = 3 * sub_depth;
  const uint64_t prefix = codes.front() >> shift;
  if (codes.back() >> shift != prefix) return InvalidArgument("a chunk's voxels must share one chunk cell");
  std::vector<uint64_t> local(codes.size());
  for (size_t i = 0; i < codes.size(); ++i) local[i] = codes[i] & ((uint64_t{1} << shift) - 1);
  ASSIGN_OR_RETURN(Svdag sub, BuildDag(local, sub_depth, options_));
  return AddSubdag(sub, prefix);
}

StatusOr<Svdag> DagMerger::Finish() {
  RETURN_IF_ERROR(impl_->Finish());
  return impl_->Emit();
}

namespace {

StatusOr<Svdag> BuildDagOn(gpu::VulkanContext* device, std::span<const uint64_t> morton, int depth, const DagBuildOptions& options) {
  RETURN_IF_ERROR(CheckDepth(depth));
  DagMerger::Impl interner(depth, options);
  if (device && !morton.empty()) {
    if (morton.back() >> (3 * depth) != 0) return InvalidArgument("Morton code outside the depth-" + std::to_string(depth) + " grid");
    ASSIGN_OR_RETURN(gpu::DagLevelHashes hashes, gpu::HashDagLevels(*device, morton, depth));
    interner.UseHashes(std::move(hashes.hashes));
  }
  RETURN_IF_ERROR(PushVoxels(interner, morton, depth));
  RETURN_IF_ERROR(interner.Finish());
  return interner.Emit();
}

// Both paths on a depth-10 grid of 2^18 voxels on a few surfaces (Vulkan after a warm-up run).
StatusOr<gpu::StageTiming> CalibrateDagHashes(gpu::VulkanContext& device) {
  std::vector<uint64_t> morton;
  for (uint32_t a = 0; a < 512; ++a) {
    for (uint32_t b = 0; b < 512; ++b) morton.push_back(MortonEncode(a * 2, b * 2, (a * 3 + b * 5) % 1024 / 2));
  }
  std::sort(morton.begin(), morton.end());
  morton.erase(std::unique(morton.begin(), morton.end()), morton.end());
  using Clock = std::chrono::steady_clock;
  const auto seconds = [](Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); };
  gpu::StageTiming timing;
  RETURN_IF_ERROR(BuildDagOn(&device, morton, 10, {}).status());
  auto start = Clock::now();
  RETURN_IF_ERROR(BuildDagOn(&device, morton, 10, {}).status());
  timing.vulkan_seconds = seconds(start);
  start = Clock::now();
  RETURN_IF_ERROR(BuildDagOn(nullptr, morton, 10, {}).status());
  timing.cpu_seconds = seconds(start);
  return timing;
}

}  // namespace

StatusOr<gpu::VulkanContext*> DagHashesDevice() { return gpu::DeviceFor(gpu::Stage::kDagHashes, CalibrateDagHashes); }


StatusOr<Svdag> BuildDag(std::span<const uint64_t> morton, int depth, const DagBuildOptions& options) {
  ASSIGN_OR_RETURN(gpu::VulkanContext* const device, DeviceForHashes(options));
  return BuildDagOn(device, morton, depth, options);
}

StatusOr<Svdag> MergeSubdags(std::span<const PlacedSubdag> parts, int depth, const DagBuildOptions& options) {
  if (parts.empty()) return InvalidArgument("nothing to merge");
  ASSIGN_OR_RETURN(DagMerger merger, DagMerger::Create(depth, depth - parts[0].dag->depth, options));
  for (const PlacedSubdag& part : parts) RETURN_IF_ERROR(merger.AddSubdag(*part.dag, part.prefix));
  return merger.Finish();
}

StatusOr<Svdag> BuildDagChunked(std::span<const uint64_t> morton, int depth, int chunk_levels,
                                const DagBuildOptions& options) {
  ASSIGN_OR_RETURN(DagMerger merger, DagMerger::Create(depth, chunk_levels, options));
  if (!morton.empty() && morton.back() >> (3 * depth) != 0) {
    return InvalidArgument("Morton code outside the depth-" + std::to_string(depth) + " grid");
  }
  const int shift = 3 * (depth - chunk_levels);
  for (size_t begin = 0; begin < morton.size();) {
    size_t end = begin;
    while (end < morton.size() && morton[end] >> shift == morton[begin] >> shift) ++end;
    RETURN_IF_ERROR(merger.AddChunk(morton.subspan(begin, end - begin)));
    begin = end;
  }
  return merger.Finish();
}

}  // namespace pointdag
