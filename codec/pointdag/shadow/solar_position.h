// Stage 10 (issue #16): where the sun is, for a georeferenced dataset and a UTC time.
//
// Contract: NOAA's solar position algorithm (the NOAA Solar Calculator's equations, after Meeus):
// azimuth in degrees clockwise from true north, elevation in degrees above the horizon including
// the NOAA approximation of atmospheric refraction. Within 0.1 degree of published tables for
// years 1901-2099. The sun is below the horizon when the refracted elevation is <= 0 (its centre);
// SunLight() then says so and every voxel is in shadow.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "pointdag/shadow/light.h"
#include "pointdag/status.h"

namespace pointdag {

struct SunPosition {
  double azimuth_deg = 0;    // clockwise from north, [0, 360)
  double elevation_deg = 0;  // above the horizon, refraction included
};

// "2026-06-21T12:00:00Z", "2026-06-21T14:00:00+02:00", fractional seconds allowed; a time without
// a zone is refused (kInvalidArgument) rather than guessed. Seconds since 1970-01-01 UTC.
StatusOr<double> ParseUtcTime(std::string_view iso8601);

// kInvalidArgument for latitudes outside [-90, 90], longitudes outside [-180, 180], NaN, or times
// outside 1901..2099.
StatusOr<SunPosition> SolarPosition(double unix_seconds, double latitude_deg, double longitude_deg);

// The sun as a light in ENU axes (x east, y north, z up): it travels from the sun towards the ground.
Light SunLight(const SunPosition& sun);

// `samples` lights at evenly spaced times from `from` to `until` inclusive (samples >= 2), or the
// one light at `from` when samples == 1. kInvalidArgument when until < from or samples is 0 or > 1440.
StatusOr<std::vector<Light>> SunLights(double from_unix_seconds, double until_unix_seconds, int samples,
                                       double latitude_deg, double longitude_deg);

}  // namespace pointdag
