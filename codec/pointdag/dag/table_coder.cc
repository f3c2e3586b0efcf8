#include "pointdag/dag/table_coder.h"

#include <string>

#include "pointdag/entropy/varint.h"

namespace pointdag {
namespace {

// Symbol 0 is never a mask; symbols 1..255 take code lengths.
constexpr int kFirstSymbol = 1;

}  // namespace

StatusOr<std::vector<uint8_t>> TableSink::Finish(std::vector<uint8_t> out) {
  std::vector<std::array<uint64_t, 256>> freq(static_cast<size_t>(depth_) + 1);
  std::array<uint64_t, 256> ref_freq{};
  for (const MaskSymbol& m : masks_) {
    if (m.bound) {
      ++ref_freq[RefSymbol(m.v, m.bound)];
    } else {
      ++freq[m.cls][m.mask];
    }
  }
  BinaryRangeEncoder rc;
  TableModels models(depth_ + 1, prefix_refs_);
  std::vector<PrefixEncoder> codes;
  codes.reserve(freq.size());
  std::array<uint8_t, 256> plain{};
  for (int s = kFirstSymbol; s < 256; ++s) plain[s] = 8;
  codes.emplace_back(plain);  // class 0 is never used
  for (int cls = 1; cls <= depth_; ++cls) {
    codes.emplace_back(WriteCodeLengths(rc, models.code, freq[cls], kFirstSymbol));
  }
  const PrefixEncoder ref_code(prefix_refs_ ? WriteCodeLengths(rc, models.code, ref_freq, 0) : plain);
  for (const Event& e : events_) {
    if (e.bound == 0) {
      rc.Encode(models.flag[e.cls], static_cast<int>(e.value));
    } else {
      EncodeGamma(rc, models.ref[e.cls], e.value + 1, std::bit_width(e.bound));
    }
  }
  const std::vector<uint8_t> ranged = rc.Finish();
  BitWriter bits;
  for (const MaskSymbol& m : masks_) {
    if (!m.bound) {
      codes[m.cls].Put(bits, m.mask);
      continue;
    }
    const int length = std::bit_width(m.v), rest = length - 1 - std::min(length - 1, 2);
    ref_code.Put(bits, static_cast<uint8_t>(RefSymbol(m.v, m.bound)));
    bits.Put(m.v & ((1u << rest) - 1), rest);
  }
  const std::vector<uint8_t> prefixed = bits.Finish();
  PutVarint(out, ranged.size());
  out.insert(out.end(), ranged.begin(), ranged.end());
  out.insert(out.end(), prefixed.begin(), prefixed.end());
  return out;
}

Status TableSource::Open(std::span<const uint8_t> payload, int depth, bool prefix_refs) {
  prefix_refs_ = prefix_refs;
  size_t pos = 0;
  uint64_t ranged = 0;
  if (!GetVarint(payload, pos, ranged)) return Truncated("geometry stream ends inside its section length");
  if (ranged > payload.size() - pos) return Truncated("geometry stream is shorter than its section length says");
  rc_.emplace(payload.subspan(pos, ranged));
  masks_.emplace(payload.subspan(pos + ranged));
  models_ = std::make_unique<TableModels>(depth + 1, prefix_refs);
  // The codes sent with the stream, one table each; classes of 8 bits a mask share the plain table.
  const auto read_code = [&](int first, const PrefixTable*& table) -> Status {
    std::array<uint8_t, 256> lengths;
    const StatusOr<bool> sent = ReadCodeLengths(*rc_, models_->code, first, lengths);
    if (!sent.ok()) return Corrupt(std::string("geometry stream holds a ") + (first ? "mask" : "reference") + " code longer than 12 bits");
    if (!*sent) {
      table = &PlainPrefixTable(first);
      return Status::Ok();
    }
    RETURN_IF_ERROR(BuildPrefixTable(lengths, built_.emplace_back()));
    table = &built_.back();
    return Status::Ok();
  };
  built_.reserve(static_cast<size_t>(depth) + 1);  // every code of the stream: the pointers stay valid
  tables_.assign(static_cast<size_t>(depth) + 1, &PlainPrefixTable(kFirstSymbol));
  for (int cls = 1; cls <= depth; ++cls) RETURN_IF_ERROR(read_code(kFirstSymbol, tables_[cls]));
  if (prefix_refs) RETURN_IF_ERROR(read_code(0, ref_table_));
  if (rc_->overrun()) return Truncated("geometry stream ends inside its code tables");
  return Status::Ok();
}

}  // namespace pointdag
