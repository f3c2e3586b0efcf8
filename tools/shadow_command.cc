#include "shadow_command.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <numeric>

#include "pointdag/container/pdag_file.h"
#include "pointdag/json_text.h"
#include "pointdag/shadow/shadow_dag.h"
#include "pointdag/shadow/solar_position.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/write/ply_writer.h"
#include "shadow_input.h"

namespace pointdag {
namespace {

constexpr int kExitBadInput = 1;
constexpr int kExitUsage = 2;
constexpr double kShadeFactor = 0.4;  // -o OUT.ply: a shadowed voxel keeps 40 % of its color

int Fail(const Status& status) {
  std::cerr << "pointdag shadow: " << status.ToString() << "\n";
  return kExitBadInput;
}

int Usage(const std::string& message) {
  std::cerr << "pointdag shadow: " << message << "\n";
  return kExitUsage;
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// "X,Y,Z": three numbers, nothing else; NaN, infinities and the zero vector are refused by LightFromDirection.
StatusOr<Light> ParseDirection(const std::string& text) {
  double v[3];
  const char* p = text.data();
  const char* end = text.data() + text.size();
  for (int i = 0; i < 3; ++i) {
    const auto [next, error] = std::from_chars(p, end, v[i]);
    const bool separator_ok = i < 2 ? (next != end && *next == ',') : next == end;
    if (error != std::errc() || !separator_ok) {
      return InvalidArgument("--direction \"" + text.substr(0, 64) + "\" is not three numbers X,Y,Z");
    }
    p = next + 1;
  }
  return LightFromDirection(v[0], v[1], v[2]);
}

struct LightPlan {
  std::vector<Light> lights;        // one, or the sun-hours samples (the first at --time)
  std::optional<SunPosition> sun;   // at --time
  double from = 0, until = 0;       // unix seconds, with --time
};

// The --direction light, or the sun from `from` to `until` at the dataset's origin.
StatusOr<LightPlan> PlanLights(const ShadowCommand& c, const ShadowInput& input, const std::optional<Light>& direction,
                               double from, double until) {
  LightPlan plan;
  if (direction) {
    plan.lights.push_back(*direction);
    return plan;
  }
  if (!input.georeferenced) {
    return InvalidArgument("--time needs a georeferenced dataset, and " + c.input +
                           " is not (a scan without a CRS, or a .pdag encoded without --georeference); "
                           "give --direction X,Y,Z in its axes instead");
  }
  plan.from = from;
  plan.until = until;
  ASSIGN_OR_RETURN(plan.sun, SolarPosition(from, input.latitude_deg, input.longitude_deg));
  ASSIGN_OR_RETURN(plan.lights, SunLights(from, until, c.samples.value_or(1), input.latitude_deg, input.longitude_deg));
  return plan;
}

nlohmann::json DescribeLight(const ShadowCommand& c, const LightPlan& plan, const ShadowInput& input) {
  const Light& light = plan.lights.front();
  nlohmann::json out = {{"direction", light.travel}, {"below_horizon", light.below_horizon}, {"sun", nullptr}};
  if (plan.sun) {
    out["sun"] = {{"time", *c.time},           {"unix_seconds", plan.from},       {"azimuth_deg", plan.sun->azimuth_deg},
                  {"elevation_deg", plan.sun->elevation_deg}, {"latitude_deg", input.latitude_deg},
                  {"longitude_deg", input.longitude_deg}};
  }
  return out;
}

// Sun hours: each of the N samples stands for span / N of the time from --time to --until.
nlohmann::json DescribeSunHours(const LightPlan& plan, const std::vector<uint16_t>& lit, double seconds) {
  const double span_hours = (plan.until - plan.from) / 3600.0;
  const double per_sample = span_hours / static_cast<double>(plan.lights.size());
  std::vector<uint64_t> histogram(plan.lights.size() + 1, 0);
  for (uint16_t n : lit) ++histogram[n];
  const double total = std::accumulate(lit.begin(), lit.end(), 0.0);
  const auto [lo, hi] = std::minmax_element(lit.begin(), lit.end());
  return {{"span_hours", span_hours},
          {"hours_per_sample", per_sample},
          {"mean_hours", lit.empty() ? 0.0 : total / static_cast<double>(lit.size()) * per_sample},
          {"min_hours", lit.empty() ? 0.0 : *lo * per_sample},
          {"max_hours", lit.empty() ? 0.0 : *hi * per_sample},
          {"never_lit", histogram.front()},
          {"always_lit", histogram.back()},
          {"lit_count_histogram", histogram},
          {"seconds", seconds}};
}

// -o OUT.ply: the voxels, colors darkened where shadowed (or by the unlit share of the samples), and
// the float property "shadowed" (0/1) or "sun_hours".
Status WritePly(const std::string& path, const ShadowInput& input, const LightPlan& plan,
                const std::vector<uint16_t>& lit, double hours_per_sample) {
  std::vector<float> values(input.grid.morton.size());
  std::vector<double> brightness(values.size());
  std::string name;
  if (plan.lights.size() == 1) {
    ASSIGN_OR_RETURN(const std::vector<uint8_t> shadowed, ShadowedVoxels(input.dag, plan.lights.front()));
    if (shadowed.size() != values.size()) return Internal("ShadowedVoxels answered for a different voxel count");
    name = "shadowed";
    for (size_t i = 0; i < values.size(); ++i) {
      values[i] = shadowed[i];
      brightness[i] = shadowed[i] ? kShadeFactor : 1.0;
    }
  } else {
    name = "sun_hours";
    for (size_t i = 0; i < values.size(); ++i) {
      values[i] = static_cast<float>(lit[i] * hours_per_sample);
      brightness[i] = kShadeFactor + (1 - kShadeFactor) * lit[i] / static_cast<double>(plan.lights.size());
    }
  }
  VoxelGrid shaded = input.grid;
  for (size_t i = 0; i < shaded.colors.size(); ++i) {
    Rgb8& c = shaded.colors[i];
    c = {static_cast<uint8_t>(c.r * brightness[i]), static_cast<uint8_t>(c.g * brightness[i]),
         static_cast<uint8_t>(c.b * brightness[i])};
  }
  return WriteVoxelsPly(path, shaded, PlyScalar{name, values});
}

void PrintSummary(const nlohmann::json& r) {
  const auto& light = r["light"];
  const auto& d = light["direction"];
  std::printf("%s: %llu voxels (depth %d, voxel %.6g)\n", r["input"].get<std::string>().c_str(),
              r["surface_voxels"].get<unsigned long long>(), r["depth"].get<int>(), r["voxel_size"].get<double>());
  std::printf("  light travels (%.4f, %.4f, %.4f)", d[0].get<double>(), d[1].get<double>(), d[2].get<double>());
  if (!light["sun"].is_null()) {
    const auto& sun = light["sun"];
    std::printf(": the sun at %s, azimuth %.2f, elevation %.2f deg (lat %.5f, lon %.5f)",
                sun["time"].get<std::string>().c_str(), sun["azimuth_deg"].get<double>(), sun["elevation_deg"].get<double>(),
                sun["latitude_deg"].get<double>(), sun["longitude_deg"].get<double>());
  }
  std::printf("%s\n", r["below_horizon"].get<bool>() ? " - below the horizon: everything in shadow" : "");
  if (r["bias"].get<double>() > 0) std::printf("  self-shadow bias %.6g voxel\n", r["bias"].get<double>());
  const double voxels = std::max(1.0, r["surface_voxels"].get<double>());
  std::printf("  shadowed %llu of them (%.1f %%)\n", r["shadowed_voxels"].get<unsigned long long>(),
              100.0 * r["shadowed_voxels"].get<double>() / voxels);
  const double dag_bytes = r["shadow_dag_bytes"].get<double>();
  const auto ratio = [&](const char* key) {  // a night's DAG can be empty: no ratio then
    char text[32] = "";
    if (dag_bytes > 0) std::snprintf(text, sizeof(text), " (%.1fx)", r[key].get<double>() / dag_bytes);
    return std::string(text);
  };
  std::printf("  shadow DAG %llu bytes at light depth %d; dense grid %llu bytes%s, shadow map %llu bytes%s; built in %.3f s\n",
              r["shadow_dag_bytes"].get<unsigned long long>(), r["light_depth"].get<int>(),
              r["dense_grid_bytes"].get<unsigned long long>(), ratio("dense_grid_bytes").c_str(),
              r["shadow_map_bytes"].get<unsigned long long>(), ratio("shadow_map_bytes").c_str(), r["build_seconds"].get<double>());
  if (!r["sun_hours"].is_null()) {
    const auto& h = r["sun_hours"];
    std::printf("  sun hours over %.2f h from %d samples: mean %.2f, min %.2f, max %.2f; never lit %llu, always lit %llu\n",
                h["span_hours"].get<double>(), r["samples"].get<int>(), h["mean_hours"].get<double>(),
                h["min_hours"].get<double>(), h["max_hours"].get<double>(), h["never_lit"].get<unsigned long long>(),
                h["always_lit"].get<unsigned long long>());
  }
  if (!r["output"].is_null()) std::printf("  wrote %s\n", r["output"].get<std::string>().c_str());
}

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

CLI::App* AddShadowCommand(CLI::App& app, ShadowCommand& c) {
  auto* cmd = app.add_subcommand(
      "shadow",
      "which voxels a directional light or the sun leaves in shadow, as a shadow DAG; sun hours from N samples.\n"
      "IN is a scan (voxelized as encode --georeference does: ENU metres when it has a CRS) or a .pdag.\n"
      "-o OUT.ply: the voxels, colors darkened in shadow, with a float property `shadowed` (0/1) or `sun_hours`;\n"
      "-o OUT.pdsh: the serialized shadow DAG (proto/SHADOW_FORMAT.md), one light only.");
  cmd->add_option("input", c.input, "scan (LAS/LAZ/PLY/PCD) or .pdag")->required();
  auto* direction = cmd->add_option("--direction", c.direction,
                                    "X,Y,Z: the direction the light travels, in the dataset's axes (z up; ENU when georeferenced)");
  auto* time = cmd->add_option("--time", c.time, "ISO 8601 with a zone (2026-06-21T12:00:00Z): the sun at the dataset's origin");
  direction->excludes(time);
  auto* until = cmd->add_option("--until", c.until, "ISO 8601: end of a sun-hours span starting at --time")->needs(time);
  auto* samples = cmd->add_option("--samples", c.samples, "sun-hours samples from --time to --until inclusive (1..1440)")
                      ->check(CLI::Range(1, 1440))
                      ->needs(until);
  until->needs(samples);
  auto* voxel = cmd->add_option("--voxel", c.voxel, "voxel size of a scan, in its units (metres when georeferenced)")
                    ->check(CLI::PositiveNumber);
  auto* depth = cmd->add_option("--depth", c.depth, "grid depth of a scan: 2^D voxels per side")->check(CLI::Range(2, 21));
  voxel->excludes(depth);
  cmd->add_option("--bias", c.bias,
                  "VOXELS (0..16, default 0): ignore occluders within this distance of a voxel's centre. With 0 (the\n"
                  "issue's exact definition) a ray may graze the neighbouring voxel's cube, so voxelized flat ground\n"
                  "shadows itself whenever the light is lower than 45 degrees (shadow acne); a bias of 0.5 / sin(elevation)\n"
                  "lights it (1 at 30 degrees, 2 at 14.5)");
  cmd->add_flag("--json", c.json, "print JSON");
  cmd->add_option("-o,--output", c.output, "OUT.ply or OUT.pdsh");
  return cmd;
}

int RunShadowCommand(const ShadowCommand& c) {
  if (!c.direction && !c.time) return Usage("give --direction X,Y,Z or --time ISO8601");
  const bool pdag = std::filesystem::path(c.input).extension() == ".pdag";
  if (pdag && (c.voxel || c.depth)) return Usage("a .pdag has its own grid; --voxel and --depth are for scans");
  if (!pdag && !c.voxel && !c.depth) return Usage("give --voxel SIZE or --depth D");
  if (!c.output.empty() && !EndsWith(c.output, ".ply") && !EndsWith(c.output, ".pdsh")) {
    return Usage("-o must name a .ply or a .pdsh file");
  }
  if (EndsWith(c.output, ".pdsh") && c.samples.value_or(1) > 1) {
    return Usage("a .pdsh holds one light's shadow DAG; write sun hours to a .ply");
  }
  // The light's arguments are checked before the (slow) load, so a typo fails at once.
  if (Status s = CheckShadowBias(c.bias); !s.ok()) return Fail(InvalidArgument("--bias: " + s.message()));
  std::optional<Light> direction;
  if (c.direction) {
    auto light = ParseDirection(*c.direction);
    if (!light.ok()) return Fail(light.status());
    direction = *light;
  }
  double from = 0, until = 0;
  if (c.time) {
    auto parsed = ParseUtcTime(*c.time);
    if (!parsed.ok()) return Fail(parsed.status());
    from = until = *parsed;
    if (c.until) {
      parsed = ParseUtcTime(*c.until);
      if (!parsed.ok()) return Fail(parsed.status());
      until = *parsed;
    }
  }
  auto input = LoadShadowInput(c.input, c.voxel, c.depth);
  if (!input.ok()) return Fail(input.status());
  auto plan = PlanLights(c, *input, direction, from, until);
  if (!plan.ok()) return Fail(plan.status());
  for (Light& light : plan->lights) light.bias_voxels = c.bias;

  auto shadow = BuildShadowDag(input->dag, plan->lights.front());
  if (!shadow.ok()) return Fail(shadow.status());
  const ShadowDagStats& stats = shadow->stats();
  nlohmann::json report = {
      {"input", c.input},
      {"depth", input->grid.depth},
      {"voxel_size", input->grid.voxel_size},
      {"surface_voxels", stats.surface_voxels},
      {"shadowed_voxels", stats.shadowed_voxels},
      {"shadow_dag_bytes", stats.shadow_dag_bytes},
      {"dense_grid_bytes", stats.dense_grid_bytes},
      {"shadow_map_bytes", stats.shadow_map_bytes},
      {"light_depth", stats.light_depth},
      {"build_seconds", stats.build_seconds},
      {"load_seconds", input->load_seconds},
      {"below_horizon", plan->lights.front().below_horizon},
      {"bias", c.bias},
      {"light", DescribeLight(c, *plan, *input)},
      {"samples", plan->lights.size()},
      {"sun_hours", nullptr},
      {"output", c.output.empty() ? nlohmann::json() : nlohmann::json(c.output)},
  };
  std::vector<uint16_t> lit;
  if (plan->lights.size() > 1) {
    const auto start = std::chrono::steady_clock::now();
    auto counts = LitSampleCounts(input->dag, plan->lights);
    if (!counts.ok()) return Fail(counts.status());
    lit = std::move(*counts);
    report["sun_hours"] = DescribeSunHours(*plan, lit, SecondsSince(start));
  }
  if (EndsWith(c.output, ".pdsh")) {
    if (Status s = WriteFileAtomically(c.output, shadow->Serialize()); !s.ok()) return Fail(s);
  } else if (!c.output.empty()) {
    const double per_sample = lit.empty() ? 0.0 : report["sun_hours"]["hours_per_sample"].get<double>();
    if (Status s = WritePly(c.output, *input, *plan, lit, per_sample); !s.ok()) return Fail(s);
  }
  if (c.json) {
    std::cout << DumpJson(report, 2) << "\n";
  } else {
    PrintSummary(report);
  }
  return 0;
}

}  // namespace pointdag
