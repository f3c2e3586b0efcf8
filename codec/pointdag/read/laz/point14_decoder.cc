#include "pointdag/read/laz/point14_decoder.h"

#include <cstring>
#include <vector>

#include "pointdag/read/byte_io.h"
#include "pointdag/read/laz/integer_decompressor.h"
#include "pointdag/read/laz/median5.h"
#include "pointdag/read/laz/gps_time_decoder.h"

namespace pointdag::laz {
namespace {

using Fields = Point14Decoder::Fields;

// LASzip's number_return_map_6ctx: which X/Y difference history a point's (returns, return) uses.
constexpr uint8_t kReturnMap[16][16] = {
    {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5}, {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
    {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3}, {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4}, {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4}, {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5}, {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5},
};

// LASzip's number_return_level_8ctx: how far the return is from the last one, at most 7.
uint32_t ReturnLevel(uint32_t n, uint32_t r) {
  const uint32_t d = n > r ? n - r : r - n;
  return d < 7 ? d : 7;
}

template <typename T>
void Store(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}

int32_t Add(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(b));
}

// The record's byte 15 holds classification flags (bits 0-3), scanner channel (4-5), scan
// direction (6) and edge of flight line (7); LASzip codes the flags without the channel.
Fields Unpack(const uint8_t* p) {
  Fields f;
  f.x = LoadLE<int32_t>(p);
  f.y = LoadLE<int32_t>(p + 4);
  f.z = LoadLE<int32_t>(p + 8);
  f.intensity = LoadLE<uint16_t>(p + 12);
  f.return_number = p[14] & 0x0F;
  f.number_of_returns = p[14] >> 4;
  f.flags = static_cast<uint8_t>((p[15] & 0x0F) | ((p[15] >> 2) & 0x30));
  f.scanner_channel = (p[15] >> 4) & 3;
  f.classification = p[16];
  f.user_data = p[17];
  f.scan_angle = LoadLE<uint16_t>(p + 18);
  f.point_source = LoadLE<uint16_t>(p + 20);
  f.gps_time = LoadLE<uint64_t>(p + 22);
  return f;
}

void Pack(const Fields& f, uint8_t* p) {
  Store(p, f.x);
  Store(p + 4, f.y);
  Store(p + 8, f.z);
  Store(p + 12, f.intensity);
  p[14] = static_cast<uint8_t>(f.return_number | (f.number_of_returns << 4));
  p[15] = static_cast<uint8_t>((f.flags & 0x0F) | (f.scanner_channel << 4) | ((f.flags & 0x30) << 2));
  p[16] = f.classification;
  p[17] = f.user_data;
  Store(p + 18, f.scan_angle);
  Store(p + 20, f.point_source);
  Store(p + 22, f.gps_time);
}

std::vector<ArithmeticModel> Models(size_t count, uint32_t symbols) {
  std::vector<ArithmeticModel> models;
  models.reserve(count);
  for (size_t i = 0; i < count; ++i) models.emplace_back(symbols);
  return models;
}

}  // namespace

// One scanner channel's models and last values (LASzip's LAScontextPOINT14).
struct Point14Decoder::Context {
  explicit Context(std::array<Layer, kLayers>& layers)
      : changed_values(Models(8, 128)),
        dx(layers[kXY].decoder(), 32, 2),
        dy(layers[kXY].decoder(), 32, 22),
        z(layers[kZ].decoder(), 32, 20),
        intensity(layers[kIntensity].decoder(), 16, 4),
        scan_angle(layers[kScanAngle].decoder(), 16, 2),
        point_source(layers[kPointSource].decoder(), 16),
        gps(layers[kGpsTime].decoder(), GpsTimeCodes::kPoint14) {}

  void Reset(const Fields& first) {
    for (auto& m : changed_values) m.Reset();
    scanner_channel.Reset();
    return_number_gps_same.Reset();
    number_of_returns.StartOver();
    return_number.StartOver();
    classification.StartOver();
    flags.StartOver();
    user_data.StartOver();
    dx.Reset();
    dy.Reset();
    z.Reset();
    intensity.Reset();
    scan_angle.Reset();
    point_source.Reset();
    gps.Reset(first.gps_time);
    for (auto& m : x_median) m.Reset();
    for (auto& m : y_median) m.Reset();
    last_z.fill(first.z);
    last_intensity.fill(first.intensity);
    last = first;
    last.gps_time_change = false;
  }

  Fields last;
  std::array<Median5, 12> x_median, y_median;
  std::array<int32_t, 8> last_z{};
  std::array<uint16_t, 8> last_intensity{};
  std::vector<ArithmeticModel> changed_values;  // by the last point's return kind and time change
  ArithmeticModel scanner_channel{3};
  ArithmeticModel return_number_gps_same{13};
  LazyModels number_of_returns{16, 16};
  LazyModels return_number{16, 16};
  LazyModels classification{64, 256};
  LazyModels flags{64, 64};
  LazyModels user_data{64, 256};
  IntegerDecompressor dx, dy, z, intensity, scan_angle, point_source;
  GpsTimeDecoder gps;
};

Point14Decoder::Point14Decoder(uint16_t version) : version_(version) {}
Point14Decoder::~Point14Decoder() = default;

Point14Decoder::Context& Point14Decoder::InitContext(uint32_t channel, const Fields& from) {
  if (!contexts_[channel]) contexts_[channel] = std::make_unique<Context>(layers_);
  Context& c = *contexts_[channel];
  c.Reset(from);
  used_[channel] = true;
  return c;
}

uint32_t Point14Decoder::Start(const uint8_t* first, const LayerSpan* layers) {
  for (uint32_t i = 0; i < kLayers; ++i) layers_[i].Start(layers[i]);
  const Fields f = Unpack(first);
  used_.fill(false);
  bad_gps_time_ = false;
  current_ = f.scanner_channel;
  InitContext(current_, f);
  return current_;
}

void Point14Decoder::Decode(uint8_t* item, uint32_t& context) {
  ArithmeticDecoder& xy = layers_[kXY].decoder();
  Context* c = contexts_[current_].get();
  Fields* last = &c->last;

  // What changed, modelled by the last point's return kind (single/first/last/middle) and time change.
  const uint32_t lpr = (last->return_number == 1 ? 1U : 0U) +
                       (last->return_number >= last->number_of_returns ? 2U : 0U) + (last->gps_time_change ? 4U : 0U);
  const uint32_t changed = xy.DecodeSymbol(c->changed_values[lpr]);
  if (changed & (1U << 6)) {  // another scanner channel: its context, new ones from this one's last point
    const uint32_t channel = (current_ + xy.DecodeSymbol(c->scanner_channel) + 1) & 3;
    if (!used_[channel]) InitContext(channel, c->last);
    current_ = channel;
    c = contexts_[channel].get();
    last = &c->last;
    last->scanner_channel = static_cast<uint8_t>(channel);
    if (version_ < 4) context = channel;
  }
  if (version_ >= 4) context = current_;
  const uint32_t gps_change = (changed >> 4) & 1;

  const uint32_t last_r = last->return_number;
  uint32_t n = last->number_of_returns;
  if (changed & (1U << 2)) {
    n = xy.DecodeSymbol(c->number_of_returns[n]);
    last->number_of_returns = static_cast<uint8_t>(n);
  }
  uint32_t r;
  switch (changed & 3) {
    case 0: r = last_r; break;
    case 1: r = (last_r + 1) & 15; break;
    case 2: r = (last_r + 15) & 15; break;
    default:
      r = gps_change ? xy.DecodeSymbol(c->return_number[last_r])
                     : (last_r + xy.DecodeSymbol(c->return_number_gps_same) + 2) & 15;
      break;
  }
  last->return_number = static_cast<uint8_t>(r);
  const uint32_t m = kReturnMap[n][r];
  const uint32_t l = ReturnLevel(n, r);
  const uint32_t cpr = (r == 1 ? 2U : 0U) + (r >= n ? 1U : 0U);  // this point's return kind
  const uint32_t single = n == 1 ? 1 : 0;

  const uint32_t xy_index = (m << 1) | gps_change;
  int32_t diff = c->dx.Decompress(c->x_median[xy_index].Get(), single);
  last->x = Add(last->x, diff);
  c->x_median[xy_index].Add(diff);
  uint32_t k = c->dx.k();
  diff = c->dy.Decompress(c->y_median[xy_index].Get(), single + (k < 20 ? (k & ~1U) : 20));
  last->y = Add(last->y, diff);
  c->y_median[xy_index].Add(diff);

  if (layers_[kZ].changed()) {
    k = (c->dx.k() + c->dy.k()) / 2;
    last->z = c->z.Decompress(c->last_z[l], single + (k < 18 ? (k & ~1U) : 18));
    c->last_z[l] = last->z;
  }
  if (layers_[kClassification].changed()) {
    const uint32_t ccc = ((last->classification & 0x1FU) << 1) + (cpr == 3 ? 1 : 0);
    last->classification =
        static_cast<uint8_t>(layers_[kClassification].decoder().DecodeSymbol(c->classification[ccc]));
  }
  if (layers_[kFlags].changed()) {
    last->flags = static_cast<uint8_t>(layers_[kFlags].decoder().DecodeSymbol(c->flags[last->flags & 0x3F]));
  }
  if (layers_[kIntensity].changed()) {
    const uint32_t index = (cpr << 1) | gps_change;
    last->intensity = static_cast<uint16_t>(c->intensity.Decompress(c->last_intensity[index], cpr));
    c->last_intensity[index] = last->intensity;
  }
  if (layers_[kScanAngle].changed() && (changed & (1U << 3))) {
    const auto angle = static_cast<int16_t>(last->scan_angle);  // predicted signed, kept as bits
    last->scan_angle = static_cast<uint16_t>(c->scan_angle.Decompress(angle, gps_change));
  }
  if (layers_[kUserData].changed()) {
    ArithmeticModel& model = c->user_data[last->user_data / 4];
    last->user_data = static_cast<uint8_t>(layers_[kUserData].decoder().DecodeSymbol(model));
  }
  if (layers_[kPointSource].changed() && (changed & (1U << 5))) {
    last->point_source = static_cast<uint16_t>(c->point_source.Decompress(last->point_source));
  }
  if (layers_[kGpsTime].changed() && gps_change) {
    if (!c->gps.Decode(last->gps_time)) bad_gps_time_ = true;
  }
  Pack(*last, item);
  last->gps_time_change = gps_change != 0;
}

Status Point14Decoder::status() const {
  static constexpr const char* kNames[kLayers] = {"returns and X/Y", "Z", "classification", "flags", "intensity",
                                                  "scan angle", "user data", "point source", "GPS time"};
  for (uint32_t i = 0; i < kLayers; ++i) RETURN_IF_ERROR(LayerStatus(layers_[i], "POINT14", kNames[i]));
  if (bad_gps_time_) {
    return Malformed("the LAZ chunk's POINT14 GPS time layer switches time sequences more often than an encoder can");
  }
  return Status::Ok();
}

}  // namespace pointdag::laz
