#include "pointdag/dag/table_coder.h"

#include "pointdag/entropy/varint.h"

namespace pointdag {
namespace {

// Symbol 0 is never a mask; symbols 1..255 take code lengths.
constexpr int kFirstSymbol = 1;

// Whether sending the lengths beats 8 bits a mask, by an estimate of the lengths' cost (the choice
// is the writer's; the stream says which it made).
bool WorthATable(const std::array<uint64_t, 256>& freq, const std::array<uint8_t, 256>& lengths) {
  uint64_t plain = 0, coded = 0, used = 0;
  for (int s = kFirstSymbol; s < 256; ++s) {
    plain += 8 * freq[s];
    coded += freq[s] * lengths[s];
    used += lengths[s] > 0 ? 1 : 0;
  }
  return coded + 5 * used + 255 / 2 < plain;
}

}  // namespace

StatusOr<std::vector<uint8_t>> TableSink::Finish(std::vector<uint8_t> out) {
  std::vector<std::array<uint64_t, 256>> freq(static_cast<size_t>(depth_) + 1);
  for (const MaskSymbol& m : masks_) ++freq[m.cls][m.mask];
  BinaryRangeEncoder rc;
  TableModels models(depth_ + 1);
  std::vector<PrefixEncoder> codes;
  codes.reserve(freq.size());
  std::array<uint8_t, 256> plain{};
  for (int s = kFirstSymbol; s < 256; ++s) plain[s] = 8;
  codes.emplace_back(plain);  // class 0 is never used
  for (int cls = 1; cls <= depth_; ++cls) {
    const std::array<uint8_t, 256> lengths = PrefixCodeLengths(freq[cls]);
    const bool coded = WorthATable(freq[cls], lengths);
    rc.Encode(models.coded, coded ? 1 : 0);
    if (coded) {
      int previous = 0;
      for (int s = kFirstSymbol; s < 256; ++s) {
        EncodeBitTree<4>(rc, models.length[previous], lengths[s]);
        previous = lengths[s];
      }
    }
    codes.emplace_back(coded ? lengths : plain);
  }
  for (const Event& e : events_) {
    if (e.bound == 0) {
      rc.Encode(models.flag[e.cls], static_cast<int>(e.value));
    } else {
      EncodeGamma(rc, models.ref[e.cls], e.value + 1, std::bit_width(e.bound));
    }
  }
  const std::vector<uint8_t> ranged = rc.Finish();
  BitWriter bits;
  for (const MaskSymbol& m : masks_) codes[m.cls].Put(bits, m.mask);
  const std::vector<uint8_t> prefixed = bits.Finish();
  PutVarint(out, ranged.size());
  out.insert(out.end(), ranged.begin(), ranged.end());
  out.insert(out.end(), prefixed.begin(), prefixed.end());
  return out;
}

Status TableSource::Open(std::span<const uint8_t> payload, int depth) {
  size_t pos = 0;
  uint64_t ranged = 0;
  if (!GetVarint(payload, pos, ranged)) return Truncated("geometry stream ends inside its section length");
  if (ranged > payload.size() - pos) return Truncated("geometry stream is shorter than its section length says");
  rc_ = std::make_unique<BinaryRangeDecoder>(payload.subspan(pos, ranged));
  masks_ = std::make_unique<PrefixDecoder>(payload.subspan(pos + ranged));
  models_ = std::make_unique<TableModels>(depth + 1);
  tables_.resize(static_cast<size_t>(depth) + 1);
  std::array<uint8_t, 256> lengths{};
  for (int cls = 1; cls <= depth; ++cls) {
    const bool coded = rc_->Decode(models_->coded) != 0;
    int previous = 0;
    for (int s = kFirstSymbol; s < 256; ++s) {
      lengths[s] = static_cast<uint8_t>(coded ? DecodeBitTree<4>(*rc_, models_->length[previous]) : 8);
      if (lengths[s] > kPrefixCodeBits) return Corrupt("geometry stream holds a mask code longer than 12 bits");
      previous = lengths[s];
    }
    RETURN_IF_ERROR(BuildPrefixTable(lengths, tables_[cls]));
  }
  if (rc_->overrun()) return Truncated("geometry stream ends inside its code tables");
  return Status::Ok();
}

}  // namespace pointdag
