#include "pointdag/read/laz/rgb14_decoder.h"

#include <cstring>
#include <vector>

#include "pointdag/read/byte_io.h"

namespace pointdag::laz {
namespace {

// Which bytes changed, then one model per byte: low/high of red (0, 1), green (2, 3), blue (4, 5).
constexpr size_t kRgbModels = 7;
// Which bytes of the near infrared changed, then its low and high byte.
constexpr size_t kNirModels = 3;

std::vector<ArithmeticModel> MakeModels(size_t count, uint32_t first_symbols) {
  std::vector<ArithmeticModel> models;
  if (count == 0) return models;
  models.reserve(count);
  models.emplace_back(first_symbols);
  for (size_t i = 1; i < count; ++i) models.emplace_back(256);
  return models;
}

// One byte: a correction to the predicted byte, modulo 256.
uint32_t Corrected(ArithmeticDecoder& dec, ArithmeticModel& model, int32_t predicted) {
  return FoldByte(static_cast<int32_t>(dec.DecodeSymbol(model)) + predicted);
}

// Red, green and blue from the last colour `last` (LASzip's RGB12 v2 scheme).
void DecodeRgb(ArithmeticDecoder& dec, std::vector<ArithmeticModel>& m, const uint16_t* last, uint16_t* out) {
  const uint32_t sym = dec.DecodeSymbol(m[0]);
  const int32_t last_lo[3] = {last[0] & 0xFF, last[1] & 0xFF, last[2] & 0xFF};
  const int32_t last_hi[3] = {last[0] >> 8, last[1] >> 8, last[2] >> 8};
  const uint32_t red_lo = (sym & 1) ? Corrected(dec, m[1], last_lo[0]) : static_cast<uint32_t>(last_lo[0]);
  const uint32_t red_hi = (sym & 2) ? Corrected(dec, m[2], last_hi[0]) : static_cast<uint32_t>(last_hi[0]);
  out[0] = static_cast<uint16_t>(red_lo | (red_hi << 8));
  if ((sym & (1 << 6)) == 0) {  // grey: green and blue equal red
    out[1] = out[2] = out[0];
    return;
  }
  // Green follows red's change; blue the mean of red's and green's.
  int32_t diff = static_cast<int32_t>(red_lo) - last_lo[0];
  uint32_t green_lo = static_cast<uint32_t>(last_lo[1]), blue_lo = static_cast<uint32_t>(last_lo[2]);
  if (sym & (1 << 2)) green_lo = Corrected(dec, m[3], ClampByte(diff + last_lo[1]));
  if (sym & (1 << 4)) {
    diff = (diff + static_cast<int32_t>(green_lo) - last_lo[1]) / 2;
    blue_lo = Corrected(dec, m[5], ClampByte(diff + last_lo[2]));
  }
  diff = static_cast<int32_t>(red_hi) - last_hi[0];
  uint32_t green_hi = static_cast<uint32_t>(last_hi[1]), blue_hi = static_cast<uint32_t>(last_hi[2]);
  if (sym & (1 << 3)) green_hi = Corrected(dec, m[4], ClampByte(diff + last_hi[1]));
  if (sym & (1 << 5)) {
    diff = (diff + static_cast<int32_t>(green_hi) - last_hi[1]) / 2;
    blue_hi = Corrected(dec, m[6], ClampByte(diff + last_hi[2]));
  }
  out[1] = static_cast<uint16_t>(green_lo | (green_hi << 8));
  out[2] = static_cast<uint16_t>(blue_lo | (blue_hi << 8));
}

uint16_t DecodeNir(ArithmeticDecoder& dec, std::vector<ArithmeticModel>& m, uint16_t last) {
  const uint32_t sym = dec.DecodeSymbol(m[0]);
  const uint32_t lo = (sym & 1) ? Corrected(dec, m[1], last & 0xFF) : (last & 0xFFU);
  const uint32_t hi = (sym & 2) ? Corrected(dec, m[2], last >> 8) : (last >> 8U);
  return static_cast<uint16_t>(lo | (hi << 8));
}

}  // namespace

// One scanner channel's models (LASzip's LAScontextRGB14 / LAScontextRGBNIR14).
struct Rgb14Decoder::Models {
  explicit Models(bool with_nir) : rgb(MakeModels(kRgbModels, 128)), nir(MakeModels(with_nir ? kNirModels : 0, 4)) {}
  void Reset() {
    for (auto& m : rgb) m.Reset();
    for (auto& m : nir) m.Reset();
  }
  std::vector<ArithmeticModel> rgb, nir;
};

Rgb14Decoder::Rgb14Decoder(bool nir, uint16_t version) : nir_(nir), follower_(version) {}
Rgb14Decoder::~Rgb14Decoder() = default;

void Rgb14Decoder::InitContext(uint32_t context, uint32_t from) {
  if (!models_[context]) models_[context] = std::make_unique<Models>(nir_);
  models_[context]->Reset();
  last_[context] = last_[from];
}

void Rgb14Decoder::Start(const uint8_t* first, const LayerSpan* layers, uint32_t context) {
  rgb_.Start(layers[0]);
  nir_layer_.Start(nir_ ? layers[1] : LayerSpan{});
  Values& v = last_[context];
  for (uint32_t i = 0; i < size() / 2; ++i) v[i] = LoadLE<uint16_t>(first + 2 * i);
  follower_.Start(context);
  InitContext(context, context);
}

void Rgb14Decoder::Decode(uint8_t* item, uint32_t context) {
  const uint32_t last = follower_.Follow(context, [this](uint32_t to, uint32_t from) { InitContext(to, from); });
  Models& m = *models_[follower_.current()];
  Values& v = last_[last];
  if (rgb_.changed()) DecodeRgb(rgb_.decoder(), m.rgb, v.data(), v.data());
  if (nir_ && nir_layer_.changed()) v[3] = DecodeNir(nir_layer_.decoder(), m.nir, v[3]);
  std::memcpy(item, v.data(), size());  // the record's little-endian uint16s
}

Status Rgb14Decoder::status() const {
  RETURN_IF_ERROR(LayerStatus(rgb_, nir_ ? "RGBNIR14" : "RGB14", "RGB"));
  return LayerStatus(nir_layer_, "RGBNIR14", "NIR");
}

}  // namespace pointdag::laz
