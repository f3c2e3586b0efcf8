// Stage 10 (issue #16): the sun's place in the sky as seen from the earth's centre, after NOAA's
// Solar Calculator (its spreadsheet's equations, Meeus' "Astronomical Algorithms" ch. 25 low
// accuracy and ch. 28 equation of time). Used by solar_position.cc; exposed so tests can check the
// intermediate quantities against published worked examples.
#pragma once

namespace pointdag {

struct SolarEphemeris {
  double apparent_longitude_deg = 0;  // lambda, nutation and aberration included
  double declination_deg = 0;         // apparent declination
  double equation_of_time_min = 0;    // apparent minus mean solar time
};

// Julian day of a time in seconds since 1970-01-01 UTC (the epoch is JD 2440587.5).
double JulianDayFromUnix(double unix_seconds);

// NOAA treats UT as TT (Delta T ~ 1 minute moves the sun by < 0.001 degree).
SolarEphemeris SunEphemeris(double julian_day);

}  // namespace pointdag
