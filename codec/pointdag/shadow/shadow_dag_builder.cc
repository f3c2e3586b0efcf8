// The shadow DAG's build (shadow_dag_impl.h): one streaming bottom-up pass over the defined cells in
// light-space Morton order, as dag/dag_builder.cc builds the geometry DAG, so only cells that hold
// a defined cell are ever visited (O(defined cells · light_depth)) and the temporaries are one
// pending node per level: Paper I's chunks exist to bound memory, and a stream needs none.
//
// Each finished subtree is resolved to a reference: all lit, all shadowed, undefined (no defined
// cell: only for siblings never visited) or a unique node. Unique nodes are interned per height
// by a 64-bit hash (Paper I, fig. 10: a node's hash comes from its masks and its children's
// hashes) confirmed by comparing contents, where children are already unique: a collision costs
// a comparison, never a wrong merge.
//
// Relaxation (Sintorn et al. 2014): a subtree whose defined cells are all lit is lit, all shadowed
// is shadowed. In a subtree holding both, the undefined cells follow options.fill: kMajority (the
// default) gives a brick's undefined bits the value most of its defined bits have, a node's
// undefined children the value most of its all-lit / all-shadowed children have: the same input
// always resolves alike, and shadow boundaries stay smooth. kMatch follows Kämpe et al. 2015's aim
// instead: a mixed brick copies a recently used brick that agrees on the defined bits, else an
// existing one with the undefined bits all lit or all shadowed; a mixed node's undefined children
// become all lit or all shadowed, whichever repeats an existing node; failing a match, lit. On the
// scans of ../shared/data kMatch came out 1-10% larger than kMajority (docs/benchmarks.md).
#include <xxhash.h>

#include <algorithm>
#include <array>

#include "pointdag/shadow/shadow_dag_impl.h"

namespace pointdag {

class ShadowTreeBuilder;

namespace {

constexpr uint32_t kUndefined = ~uint32_t{0};
constexpr uint32_t kLit = kUndefined - 1;
constexpr uint32_t kShadowed = kUndefined - 2;
constexpr uint32_t kNotFound = kUndefined;
constexpr size_t kBrickCache = 64;  // recently used bricks tried against a mixed brick

bool IsNode(uint32_t ref) { return ref < kShadowed; }

// Unique subtrees of one height (2 = bricks, 3.. = internal nodes).
struct Table {
  std::vector<uint64_t> hash;
  std::vector<uint64_t> brick;     // height 2
  std::vector<uint16_t> masks;     // height >= 3: pointer_mask | full_mask << 8
  std::vector<uint32_t> first;     // height >= 3: index of the first child in `children`
  std::vector<uint32_t> children;  // ids on height - 1
  std::vector<uint32_t> slots;     // open addressing: id + 1, 0 = free

  size_t size() const { return hash.size(); }
  size_t Bytes() const {
    return hash.capacity() * 8 + brick.capacity() * 8 + masks.capacity() * 2 + first.capacity() * 4 +
           children.capacity() * 4 + slots.capacity() * 4;
  }
};

struct Pending {
  bool active = false;
  uint64_t key = 0;
  std::array<uint32_t, 8> child{};
};

}  // namespace

class ShadowTreeBuilder {
 public:
  ShadowTreeBuilder(int light_depth, const ShadowBuildOptions& options)
      : depth_(light_depth), options_(options), tables_(light_depth + 1), pending_(light_depth + 1) {
    for (auto& p : pending_) p.child.fill(kUndefined);
  }

  Status Add(uint64_t cell) {
    const uint64_t code = cell >> 1;
    if (started_ && code <= last_code_) return InvalidArgument("defined cells are not sorted by strictly increasing code");
    if (code >> (3 * depth_) != 0) return InvalidArgument("a defined cell lies outside the light-space grid");
    if (started_ && (code >> 6) != brick_key_) FlushBrick();
    started_ = true;
    last_code_ = code;
    brick_key_ = code >> 6;
    defined_ |= uint64_t{1} << (code & 63);
    value_ |= (cell & 1) << (code & 63);
    return Status::Ok();
  }

  // A whole subtree of `height` (2: a brick) at cell `key`, in increasing Morton order, everything
  // defined (the free-space mode of shadow_free_space.cc; not mixed with Add).
  void AddUniform(int height, uint64_t key, bool shadowed) {
    // Nodes still open below `height` come before this subtree and cannot contain it: done.
    for (int below = 3; below <= height; ++below) {
      if (pending_[below].active) Flush(below);
    }
    if (height == depth_) {
      root_ = shadowed ? kShadowed : kLit;
    } else {
      Push(height, key, shadowed ? kShadowed : kLit);
    }
  }
  void AddBrick(uint64_t key, uint64_t mask) { Push(2, key, ResolveBrick(~uint64_t{0}, mask)); }

  void Finish(ShadowDag::Impl& out) {
    if (started_) FlushBrick();
    for (int height = 3; height <= depth_; ++height) {
      if (pending_[height].active) Flush(height);
    }
    Emit(out);
  }

 private:
  void FlushBrick() {
    Push(2, brick_key_, ResolveBrick(defined_, value_));
    defined_ = value_ = 0;
  }

  // Subtree `ref` of `height` covers the cell `key` (its Morton code at that height).
  void Push(int height, uint64_t key, uint32_t ref) {
    Pending& p = pending_[height + 1];
    if (p.active && p.key != key >> 3) Flush(height + 1);
    p.active = true;
    p.key = key >> 3;
    p.child[key & 7] = ref;
  }

  void Flush(int height) {
    Pending& p = pending_[height];
    const uint32_t ref = ResolveNode(height, p.child);
    p.active = false;
    p.child.fill(kUndefined);
    if (height == depth_) {
      root_ = ref;
    } else {
      Push(height, p.key, ref);
    }
  }

  uint32_t ResolveBrick(uint64_t defined, uint64_t value) {
    const bool relax = options_.relax_undefined;
    if (value == 0) return kLit;
    if (value == (relax ? defined : ~uint64_t{0})) return kShadowed;
    uint64_t brick = value;  // undefined bits lit
    if (relax && options_.fill == UndefinedFill::kMajority &&
        2 * __builtin_popcountll(value) > __builtin_popcountll(defined)) {
      brick = value | ~defined;
    }
    if (relax && options_.fill == UndefinedFill::kMatch) {
      const auto hit = std::find_if(cache_.begin(), cache_.end(), [&](uint64_t b) { return (b & defined) == value; });
      if (hit != cache_.end()) {
        brick = *hit;
      } else if (FindBrick(value) == kNotFound && FindBrick(value | ~defined) != kNotFound) {
        brick = value | ~defined;
      }
      Remember(brick);
    }
    return InternBrick(brick);
  }

  uint32_t ResolveNode(int height, std::array<uint32_t, 8> child) {
    const bool relax = options_.relax_undefined;
    if (!relax) child = Filled(child, kLit);
    int lit = 0, shadowed = 0;
    bool node = false, undefined = false;
    for (uint32_t c : child) {
      lit += c == kLit;
      shadowed += c == kShadowed;
      node |= IsNode(c);
      undefined |= c == kUndefined;
    }
    // Only lit (shadowed) among the defined: lit (shadowed). Never all undefined: a pushed child is defined.
    if (!node && !shadowed) return kLit;
    if (!node && !lit) return kShadowed;
    uint32_t fill = kLit;
    if (options_.fill == UndefinedFill::kMajority && shadowed > lit) fill = kShadowed;
    if (options_.fill == UndefinedFill::kMatch && undefined) {
      if (FindNode(height, Filled(child, kLit)) == kNotFound && FindNode(height, Filled(child, kShadowed)) != kNotFound) {
        fill = kShadowed;
      }
    }
    return InternNode(height, Filled(child, fill));
  }

  static std::array<uint32_t, 8> Filled(std::array<uint32_t, 8> child, uint32_t fill) {
    for (uint32_t& c : child) c = c == kUndefined ? fill : c;
    return child;
  }

  void Remember(uint64_t brick) {
    const auto at = std::find(cache_.begin(), cache_.end(), brick);
    if (at != cache_.end()) cache_.erase(at);
    if (cache_.size() == kBrickCache) cache_.pop_back();
    cache_.insert(cache_.begin(), brick);
  }

  uint64_t BrickHash(uint64_t brick) const { return XXH3_64bits(&brick, sizeof(brick)) & options_.hash_mask; }

  // A node's key: masks, then its children's hashes (Paper I) or ids (for the comparison).
  struct NodeKey {
    uint16_t masks = 0;
    int n = 0;
    std::array<uint32_t, 8> ids{};
    uint64_t hash = 0;
  };

  NodeKey MakeKey(int height, const std::array<uint32_t, 8>& child) const {
    NodeKey key;
    std::array<uint64_t, 9> words{};
    for (uint32_t octant = 0; octant < 8; ++octant) {
      const uint32_t c = child[octant];
      if (IsNode(c)) {
        key.masks = static_cast<uint16_t>(key.masks | 1u << octant);
        key.ids[key.n] = c;
        words[1 + key.n++] = tables_[height - 1].hash[c];
      } else if (c == kShadowed) {
        key.masks = static_cast<uint16_t>(key.masks | 1u << (8 + octant));
      }
    }
    words[0] = key.masks;
    key.hash = XXH3_64bits(words.data(), sizeof(uint64_t) * (1 + key.n)) & options_.hash_mask;
    return key;
  }

  bool SameNode(const Table& t, uint32_t id, const NodeKey& key) const {
    return t.masks[id] == key.masks && std::equal(key.ids.begin(), key.ids.begin() + key.n, t.children.begin() + t.first[id]);
  }

  uint32_t FindBrick(uint64_t brick) const {
    const Table& t = tables_[2];
    return Probe(t, BrickHash(brick), [&](uint32_t id) { return t.brick[id] == brick; }).first;
  }

  uint32_t FindNode(int height, const std::array<uint32_t, 8>& child) const {
    const Table& t = tables_[height];
    const NodeKey key = MakeKey(height, child);
    return Probe(t, key.hash, [&](uint32_t id) { return SameNode(t, id, key); }).first;
  }

  uint32_t InternBrick(uint64_t brick) {
    Table& t = tables_[2];
    const uint64_t h = BrickHash(brick);
    return Intern(t, h, [&](uint32_t id) { return t.brick[id] == brick; }, [&] { t.brick.push_back(brick); });
  }

  uint32_t InternNode(int height, const std::array<uint32_t, 8>& child) {
    Table& t = tables_[height];
    const NodeKey key = MakeKey(height, child);
    return Intern(t, key.hash, [&](uint32_t id) { return SameNode(t, id, key); }, [&] {
      t.masks.push_back(key.masks);
      t.first.push_back(static_cast<uint32_t>(t.children.size()));
      t.children.insert(t.children.end(), key.ids.begin(), key.ids.begin() + key.n);
    });
  }

  // (id, kNotFound) when found, else (kNotFound, the free slot where it would go).
  template <typename Equal>
  static std::pair<uint32_t, size_t> Probe(const Table& t, uint64_t h, Equal&& equal) {
    if (t.slots.empty()) return {kNotFound, 0};
    const size_t mask = t.slots.size() - 1;
    for (size_t i = Slot(h, mask);; i = (i + 1) & mask) {
      const uint32_t entry = t.slots[i];
      if (entry == 0) return {kNotFound, i};
      if (t.hash[entry - 1] == h && equal(entry - 1)) return {entry - 1, 0};
    }
  }

  template <typename Equal, typename Append>
  static uint32_t Intern(Table& t, uint64_t h, Equal&& equal, Append&& append) {
    if (t.size() * 2 >= t.slots.size()) Grow(t);
    const auto [found, slot] = Probe(t, h, equal);
    if (found != kNotFound) return found;
    const uint32_t id = static_cast<uint32_t>(t.size());
    t.hash.push_back(h);
    append();
    t.slots[slot] = id + 1;
    return id;
  }

  static size_t Slot(uint64_t h, size_t mask) { return static_cast<size_t>((h * 0x9E3779B97F4A7C15ull) >> 20) & mask; }

  static void Grow(Table& t) {
    t.slots.assign(std::max<size_t>(64, t.slots.size() * 2), 0);
    const size_t mask = t.slots.size() - 1;
    for (uint32_t id = 0; id < t.size(); ++id) {
      size_t i = Slot(t.hash[id], mask);
      while (t.slots[i] != 0) i = (i + 1) & mask;
      t.slots[i] = id + 1;
    }
  }

  // Records level by level from the root, each level in first-seen order (every interned node is
  // some node's child, so all are reachable).
  void Emit(ShadowDag::Impl& out) {
    size_t peak = 0;
    for (const Table& t : tables_) peak += t.Bytes();
    out.nodes.clear();
    out.leaves = tables_[2].brick;
    if (root_ == kLit || root_ == kUndefined || root_ == kShadowed) {
      out.root = root_ == kShadowed ? ShadowRoot::kShadowed : ShadowRoot::kLit;
      out.stats.build_peak_bytes = peak;
      return;
    }
    out.root = ShadowRoot::kNode;
    std::vector<std::vector<uint32_t>> offset(depth_ + 1);
    uint32_t words = 0;
    for (int height = depth_; height >= 3; --height) {
      const Table& t = tables_[height];
      offset[height].resize(t.size());
      for (uint32_t id = 0; id < t.size(); ++id) {
        offset[height][id] = words;
        words += 1 + static_cast<uint32_t>(__builtin_popcount(t.masks[id] & 0xFFu));
      }
    }
    out.nodes.reserve(words);
    for (int height = depth_; height >= 3; --height) {
      const Table& t = tables_[height];
      for (uint32_t id = 0; id < t.size(); ++id) {
        out.nodes.push_back(t.masks[id]);
        const int n = __builtin_popcount(t.masks[id] & 0xFFu);
        for (int i = 0; i < n; ++i) {
          const uint32_t c = t.children[t.first[id] + i];
          out.nodes.push_back(height == 3 ? c : offset[height - 1][c]);
        }
      }
    }
    out.stats.build_peak_bytes = peak + out.nodes.capacity() * 4 + out.leaves.capacity() * 8 + words * 4;
  }

  int depth_;
  ShadowBuildOptions options_;
  std::vector<Table> tables_;
  std::vector<Pending> pending_;
  std::vector<uint64_t> cache_;
  bool started_ = false;
  uint64_t last_code_ = 0, brick_key_ = 0, defined_ = 0, value_ = 0;
  uint32_t root_ = kUndefined;
};

ShadowSubtreeSink::ShadowSubtreeSink(int light_depth, const ShadowBuildOptions& options)
    : builder_(std::make_unique<ShadowTreeBuilder>(light_depth, options)) {}
ShadowSubtreeSink::~ShadowSubtreeSink() = default;
void ShadowSubtreeSink::Uniform(int height, uint64_t key, bool shadowed) { builder_->AddUniform(height, key, shadowed); }
void ShadowSubtreeSink::Brick(uint64_t key, uint64_t mask) { builder_->AddBrick(key, mask); }
void ShadowSubtreeSink::Finish(ShadowDag::Impl& out) {
  builder_->Finish(out);
  out.FillSizeStats();
}

Status BuildShadowArrays(std::span<const uint64_t> defined_cells, int light_depth, const ShadowBuildOptions& options,
                         ShadowDag::Impl& out) {
  if (light_depth < 3 || light_depth > kMaxLightDepth) return InvalidArgument("light depth must be in 3..21");
  ShadowTreeBuilder builder(light_depth, options);
  for (uint64_t cell : defined_cells) RETURN_IF_ERROR(builder.Add(cell));
  builder.Finish(out);
  out.FillSizeStats();
  return Status::Ok();
}

}  // namespace pointdag
