#include "pointdag/shadow/solar_ephemeris.h"

#include <cmath>
#include <numbers>

namespace pointdag {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
double SinDeg(double d) { return std::sin(d * kRadPerDeg); }
double CosDeg(double d) { return std::cos(d * kRadPerDeg); }

}  // namespace

double JulianDayFromUnix(double unix_seconds) { return unix_seconds / 86400.0 + 2440587.5; }

SolarEphemeris SunEphemeris(double julian_day) {
  // Julian centuries from J2000.0.
  const double t = (julian_day - 2451545.0) / 36525.0;
  const double mean_longitude = std::fmod(280.46646 + t * (36000.76983 + t * 0.0003032), 360.0);
  const double mean_anomaly = 357.52911 + t * (35999.05029 - 0.0001537 * t);
  const double eccentricity = 0.016708634 - t * (0.000042037 + 0.0000001267 * t);
  const double equation_of_centre = SinDeg(mean_anomaly) * (1.914602 - t * (0.004817 + 0.000014 * t)) +
                                    SinDeg(2 * mean_anomaly) * (0.019993 - 0.000101 * t) +
                                    SinDeg(3 * mean_anomaly) * 0.000289;
  const double true_longitude = mean_longitude + equation_of_centre;
  // Omega, the longitude of the moon's ascending node: nutation and aberration in one term.
  const double omega = 125.04 - 1934.136 * t;
  const double apparent_longitude = true_longitude - 0.00569 - 0.00478 * SinDeg(omega);
  const double mean_obliquity =
      23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.00059 - t * 0.001813))) / 60.0) / 60.0;
  const double obliquity = mean_obliquity + 0.00256 * CosDeg(omega);

  SolarEphemeris out;
  out.apparent_longitude_deg = std::fmod(apparent_longitude + 360.0, 360.0);
  out.declination_deg = std::asin(SinDeg(obliquity) * SinDeg(apparent_longitude)) / kRadPerDeg;
  // Meeus (28.3), Smart's series for the equation of time, in minutes of time.
  const double y = std::pow(std::tan(obliquity * kRadPerDeg / 2.0), 2);
  const double e_rad = y * SinDeg(2 * mean_longitude) - 2 * eccentricity * SinDeg(mean_anomaly) +
                       4 * eccentricity * y * SinDeg(mean_anomaly) * CosDeg(2 * mean_longitude) -
                       0.5 * y * y * SinDeg(4 * mean_longitude) -
                       1.25 * eccentricity * eccentricity * SinDeg(2 * mean_anomaly);
  out.equation_of_time_min = 4.0 * e_rad / kRadPerDeg;
  return out;
}

}  // namespace pointdag
