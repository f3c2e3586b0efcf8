#include "pointdag/bench/corpus_case.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <string>

#include "pointdag/compare/scorecard.h"
#include "pointdag/container/pdag_file.h"
#include "pointdag/pipeline.h"

namespace pointdag {
namespace {

constexpr double kSpeedTarget = 38.0;  // the daemon's tiles' target

uint64_t PeakRssBytes() {
  std::ifstream status("/proc/self/status");
  std::string key;
  uint64_t kb = 0;
  while (status >> key) {
    if (key == "VmHWM:" && status >> kb) return kb * 1024;
  }
  return 0;
}

nlohmann::json Row(const nlohmann::json& codec, const std::string& name) {
  return {{"codec", name},
          {"target_psnr", codec["target_psnr"]},
          {"psnr_y", codec["psnr_y"]},
          {"psnr_y_vs_original", codec["psnr_y_vs_original"]},
          {"color_bits_per_voxel", codec["color_bits_per_voxel"]},
          {"bits_per_point", codec["total_bits_per_voxel"]}};
}

// VBR and fixed3 rows as they are; of the image mappings (every codec, both curves) the smallest
// at each target, named "image" with its codec and curve beside; lossless.
nlohmann::json OursRows(const nlohmann::json& codecs, const std::vector<double>& targets) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& c : codecs) {
    const std::string name = c["name"];
    if (name == "vbr" || name == "fixed3" || name == "hierarchical") rows.push_back(Row(c, name));
    if (name == "lossless") rows.push_back(Row(c, "lossless"));
  }
  for (double target : targets) {
    const nlohmann::json* best = nullptr;
    for (const auto& c : codecs) {
      if (c["curve"].is_null() || c["target_psnr"].is_null() || c["target_psnr"].get<double>() != target) continue;
      if (!best || c["total_bits_per_voxel"].get<double>() < (*best)["total_bits_per_voxel"].get<double>()) best = &c;
    }
    if (!best) continue;
    nlohmann::json row = Row(*best, "image");
    row["image_codec"] = (*best)["name"];
    row["curve"] = (*best)["curve"];
    rows.push_back(std::move(row));
  }
  return rows;
}

StatusOr<nlohmann::json> Measure(const CorpusCase& c) {
  EncodeOptions options;
  options.voxel_size = c.voxel;
  options.colors = {ColorCodec::kVariableRate, kSpeedTarget};
  ASSIGN_OR_RETURN(const EncodedScan encoded, EncodeScan(c.scan, options));
  ASSIGN_OR_RETURN(nlohmann::json card, BuildScorecard(encoded, c.targets));
  const double voxels = static_cast<double>(encoded.grid.morton.size());

  const std::vector<uint8_t> bytes = SerializePdag(encoded.file);
  double decode_seconds = INFINITY;
  for (int pass = 0; pass < 3; ++pass) {  // best of three, as Draco's decode
    const auto start = std::chrono::steady_clock::now();
    ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(bytes));
    RETURN_IF_ERROR(DecodePdag(file).status());
    decode_seconds = std::min(decode_seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  const double encode_seconds = encoded.seconds.build + encoded.seconds.encode + encoded.seconds.colors;
  const nlohmann::json& draco = card["draco"];
  return nlohmann::json{
      {"scan", c.scan.filename().string()},
      {"path", c.scan.string()},
      {"voxel", c.voxel},
      {"voxel_derived", c.voxel_derived},
      {"targets", c.targets},
      {"points", card["points"]},
      {"voxels", card["voxels"]},
      {"geometry_bits_per_voxel", card["geometry_bits_per_voxel"]},
      {"draco_bits_per_point", card["draco_bits_per_point"]},
      {"draco", {{"method", draco["method"]}, {"speed", draco["speed"]}, {"bytes", draco["bytes"]}}},
      {"original", card["original"]},
      {"ours", OursRows(card["codecs"], c.targets)},
      {"speed",
       {{"ours_encode_points_per_second", voxels / encode_seconds},
        {"ours_decode_points_per_second", voxels / decode_seconds},
        {"draco_encode_points_per_second", voxels / draco["level10_encode_s"].get<double>()},
        {"draco_decode_points_per_second", voxels / draco["decode_s"].get<double>()},
        {"ours_encode_target_psnr", kSpeedTarget}}},
      {"peak_rss_bytes", PeakRssBytes()},
  };
}

}  // namespace

nlohmann::json RunCorpusCase(const CorpusCase& c) {
  auto measured = Measure(c);
  if (!measured.ok()) return {{"scan", c.scan.filename().string()}, {"voxel", c.voxel}, {"error", measured.status().ToString()}};
  return *measured;
}

double JsonNumber(const nlohmann::json& object, const char* key) {
  const auto it = object.find(key);
  return it != object.end() && it->is_number() ? it->get<double>() : NAN;
}

std::string CodecRowKey(const nlohmann::json& row) {
  const std::string codec = row.value("codec", "?");
  const auto target = row.find("target_psnr");
  if (target == row.end() || !target->is_number()) return codec;
  const double t = target->get<double>();
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%s@%g", codec.c_str(), t);
  return buf;
}

}  // namespace pointdag
