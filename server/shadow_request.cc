#include "shadow_request.h"

#include <cmath>
#include <ctime>
#include <string>

#include "pointdag/shadow/solar_position.h"

namespace pointdag::server {
namespace {

constexpr const char* kForms =
    "{\"direction\": [x, y, z]}, {\"time\": \"2026-06-21T12:00:00Z\"} or {\"time\": ..., \"until\": ..., \"samples\": N}";

// "2026-06-21T10:00:00Z" (milliseconds when the time has a fraction).
std::string FormatUtc(double unix_seconds) {
  const double whole = std::floor(unix_seconds);
  const auto ms = static_cast<int>(std::lround((unix_seconds - whole) * 1000));
  const auto t = static_cast<std::time_t>(whole);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[40];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%S", &tm);
  std::string out = text;
  if (ms > 0 && ms < 1000) {
    char fraction[8];
    std::snprintf(fraction, sizeof(fraction), ".%03d", ms);
    out += fraction;
  }
  return out + "Z";
}

StatusOr<double> TimeMember(const nlohmann::json& request, const char* name) {
  const nlohmann::json& value = request.at(name);
  if (!value.is_string()) return InvalidArgument(std::string(name) + " must be an ISO 8601 time with a zone, e.g. \"2026-06-21T12:00:00Z\"");
  auto seconds = ParseUtcTime(value.get<std::string>());
  if (!seconds.ok()) return InvalidArgument(std::string(name) + ": " + seconds.status().message());
  return *seconds;
}

StatusOr<ShadowPlan> PlanDirection(const nlohmann::json& request) {
  if (request.contains("until") || request.contains("samples")) {
    return InvalidArgument("until and samples go with a time, not with a direction");
  }
  const nlohmann::json& d = request.at("direction");
  if (!d.is_array() || d.size() != 3 || !d[0].is_number() || !d[1].is_number() || !d[2].is_number()) {
    return InvalidArgument("direction must be three numbers [x, y, z]: the way the light travels (z up)");
  }
  auto light = LightFromDirection(d[0].get<double>(), d[1].get<double>(), d[2].get<double>());
  if (!light.ok()) return InvalidArgument("direction: " + light.status().message());
  ShadowPlan plan;
  plan.kind = ShadowKind::kDirection;
  plan.lights = {*light};
  plan.request = {{"direction", d}};
  plan.description = {{"kind", "direction"}, {"samples", 1}, {"direction", light->travel}};
  return plan;
}

// The lights of the body's direction, time, or sun-hours form (members already checked by name).
StatusOr<ShadowPlan> PlanLights(const nlohmann::json& request, const nlohmann::json& dataset_meta) {
  if (request.contains("direction") == request.contains("time")) {
    return InvalidArgument(std::string("give either a direction or a time: ") + kForms);
  }
  if (request.contains("direction")) return PlanDirection(request);
  if (request.contains("until") != request.contains("samples")) {
    return InvalidArgument("sun hours need both until and samples (or give a time alone)");
  }
  ASSIGN_OR_RETURN(const double time, TimeMember(request, "time"));
  const nlohmann::json frame = dataset_meta.is_object() ? dataset_meta.value("frame", nlohmann::json()) : nlohmann::json();
  const nlohmann::json origin = frame.is_object() ? frame.value("enu_origin", nlohmann::json()) : nlohmann::json();
  const bool georeferenced = frame.is_object() && frame.contains("georeferenced") && frame["georeferenced"].is_boolean() &&
                             frame["georeferenced"].get<bool>() && origin.is_object() &&
                             origin.contains("lat") && origin["lat"].is_number() && origin.contains("lon") && origin["lon"].is_number();
  if (!georeferenced) {
    return InvalidArgument("the dataset is not georeferenced, so the sun's place in its sky is unknown: give a direction "
                           "instead ({\"direction\": [x, y, z]}, the way the light travels)");
  }
  const double lat = origin["lat"].get<double>(), lon = origin["lon"].get<double>();
  ShadowPlan plan;
  if (!request.contains("until")) {
    auto sun = SolarPosition(time, lat, lon);
    if (!sun.ok()) return InvalidArgument("time: " + sun.status().message());
    const Light light = SunLight(*sun);
    plan.kind = ShadowKind::kDirection;
    plan.lights = {light};
    plan.request = {{"time", request["time"]}};
    plan.description = {{"kind", "direction"}, {"samples", 1}, {"direction", light.travel}, {"time", FormatUtc(time)},
                        {"sun", {{"azimuth_deg", sun->azimuth_deg}, {"elevation_deg", sun->elevation_deg},
                                 {"below_horizon", light.below_horizon}}}};
    return plan;
  }
  ASSIGN_OR_RETURN(const double until, TimeMember(request, "until"));
  const nlohmann::json& samples = request["samples"];
  if (!samples.is_number_integer() || samples.get<double>() < 1 || samples.get<double>() > kMaxShadowSamples) {
    return InvalidArgument("samples must be an integer from 1 to " + std::to_string(kMaxShadowSamples));
  }
  const int n = static_cast<int>(samples.get<double>());
  if (until < time) return InvalidArgument("until must not be before time");
  auto lights = SunLights(time, until, n, lat, lon);
  if (!lights.ok()) return InvalidArgument(lights.status().message());
  plan.kind = ShadowKind::kSunHours;
  plan.lights = std::move(*lights);
  plan.request = {{"time", request["time"]}, {"until", request["until"]}, {"samples", n}};
  plan.description = {{"kind", "sun_hours"}, {"samples", n}, {"time", FormatUtc(time)}, {"until", FormatUtc(until)},
                      {"hours", (until - time) / 3600}};
  return plan;
}

}  // namespace

StatusOr<ShadowPlan> PlanShadows(const nlohmann::json& request, const nlohmann::json& dataset_meta) {
  if (!request.is_object()) return InvalidArgument(std::string("the body must be a JSON object: ") + kForms);
  for (const auto& [key, value] : request.items()) {
    if (key != "direction" && key != "time" && key != "until" && key != "samples" && key != "bias") {
      return InvalidArgument("unknown member '" + key + "' (direction, time, until, samples, bias)");
    }
  }
  double bias = 0;
  if (request.contains("bias")) {
    const nlohmann::json& b = request["bias"];
    if (!b.is_number() || !CheckShadowBias(b.get<double>()).ok()) {
      return InvalidArgument("bias must be a number of voxels from 0 to 16 (the self-shadow bias; 0 is the exact definition)");
    }
    bias = b.get<double>();
  }
  ASSIGN_OR_RETURN(ShadowPlan plan, PlanLights(request, dataset_meta));
  for (Light& light : plan.lights) light.bias_voxels = bias;
  if (request.contains("bias")) plan.request["bias"] = bias;
  plan.description["bias"] = bias;
  return plan;
}

}  // namespace pointdag::server
