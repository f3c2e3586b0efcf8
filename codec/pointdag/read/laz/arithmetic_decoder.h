// LASzip's adaptive arithmetic decoder (after Amir Said's FastAC) and its two adaptive models.
//
// Contract: the decoder reads only inside [begin, end). Reading past the end yields zero bytes and
// sets overran(); callers check it once per batch and turn it into a Truncated/Corrupt status, so a
// hostile stream can never read outside its chunk, loop forever or allocate. Every arithmetic
// operation is on unsigned 32-bit values exactly as in LASzip, so decoding is bit-exact with it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pointdag::laz {

// An adaptive binary model: the probability of a 0, re-estimated every few bits.
class ArithmeticBitModel {
 public:
  ArithmeticBitModel() { Reset(); }
  void Reset();

 private:
  friend class ArithmeticDecoder;
  void Update();
  uint32_t bit_0_count_ = 1, bit_count_ = 2, bit_0_prob_ = 0, bits_until_update_ = 4, update_cycle_ = 4;
};

// An adaptive model over `symbols` symbols (2..2048), with LASzip's decoder lookup table above 16.
class ArithmeticModel {
 public:
  explicit ArithmeticModel(uint32_t symbols);
  void Reset();
  uint32_t symbols() const { return symbols_; }

 private:
  friend class ArithmeticDecoder;
  void Update();
  uint32_t symbols_;
  uint32_t last_symbol_;
  uint32_t table_size_ = 0, table_shift_ = 0;
  uint32_t total_count_ = 0, update_cycle_ = 0, symbols_until_update_ = 0;
  std::vector<uint32_t> distribution_, symbol_count_, decoder_table_;
};

class ArithmeticDecoder {
 public:
  ArithmeticDecoder() = default;
  // Starts decoding the bytes [begin, end): reads the first four bytes of the code value.
  void Init(const uint8_t* begin, const uint8_t* end);

  uint32_t DecodeBit(ArithmeticBitModel& model);
  uint32_t DecodeSymbol(ArithmeticModel& model);
  // Raw (unmodelled) values, as LASzip writes them with writeBits/writeShort/writeInt/writeInt64.
  uint32_t ReadBits(uint32_t bits);  // 1..32
  uint32_t ReadByte();
  uint32_t ReadShort();
  uint32_t ReadInt();
  uint64_t ReadInt64();

  bool overran() const { return overran_; }
  // Bytes taken from the stream so far (after a finished chunk: where the next one starts).
  size_t consumed() const { return static_cast<size_t>(next_ - begin_); }

 private:
  uint8_t NextByte() {
    if (next_ < end_) return *next_++;
    overran_ = true;
    return 0;
  }
  void Renormalize();

  const uint8_t* begin_ = nullptr;
  const uint8_t* next_ = nullptr;
  const uint8_t* end_ = nullptr;
  uint32_t value_ = 0, length_ = 0;
  bool overran_ = false;
};

}  // namespace pointdag::laz
