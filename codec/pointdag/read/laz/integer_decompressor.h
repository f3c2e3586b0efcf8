// LASzip's IntegerCompressor, decoding side: an integer is coded as a correction to a prediction,
// first the correction's bit length k (one adaptive model per context), then its value within the
// k-bit range (adaptive models for the high bits, raw bits below them).
#pragma once

#include <cstdint>
#include <vector>

#include "pointdag/read/laz/arithmetic_decoder.h"

namespace pointdag::laz {

class IntegerDecompressor {
 public:
  // bits: width of the values (corrections wrap modulo 2^bits); contexts: how many k-models;
  // bits_high: corrections longer than this code their low bits raw; range: a non-power-of-two range.
  IntegerDecompressor(ArithmeticDecoder& decoder, uint32_t bits = 16, uint32_t contexts = 1, uint32_t bits_high = 8,
                      uint32_t range = 0);
  // Starts every model over (LASzip's initDecompressor).
  void Reset();
  int32_t Decompress(int32_t prediction, uint32_t context = 0);
  // The bit length of the last correction (item coders use it to pick the next context).
  uint32_t k() const { return k_; }

 private:
  int32_t ReadCorrector(ArithmeticModel& bits_model);

  ArithmeticDecoder* decoder_;
  uint32_t contexts_, bits_high_;
  uint32_t corr_bits_ = 0, corr_range_ = 0;
  int32_t corr_min_ = 0;
  uint32_t k_ = 0;
  std::vector<ArithmeticModel> bits_models_;   // one per context: the correction's bit length
  ArithmeticBitModel corrector0_;              // k == 0: the correction is 0 or 1
  std::vector<ArithmeticModel> correctors_;    // k == 1..corr_bits (index k - 1)
};

}  // namespace pointdag::laz
