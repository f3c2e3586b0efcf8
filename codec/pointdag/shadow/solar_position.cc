#include "pointdag/shadow/solar_position.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "pointdag/shadow/solar_ephemeris.h"

namespace pointdag {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr double kSecondsPerDay = 86400.0;
// 1901-01-01T00:00:00Z and 2100-01-01T00:00:00Z: NOAA's equations are stated for 1901..2099.
constexpr double kFirstValidUnix = -2177452800.0;
constexpr double kEndValidUnix = 4102444800.0;
constexpr int kMaxSamples = 1440;  // one a minute over a day

// Days from 1970-01-01 to a proleptic Gregorian date (H. Hinnant's days_from_civil).
int64_t DaysFromCivil(int64_t y, int m, int d) {
  y -= m <= 2;
  const int64_t era = (y >= 0 ? y : y - 399) / 400;
  const int64_t yoe = y - era * 400;
  const int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

int DaysInMonth(int y, int m) {
  static constexpr int kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  return m == 2 && leap ? 29 : kDays[m - 1];
}

// Reads exactly `n` decimal digits at `pos` and advances it; false on anything else.
bool Digits(std::string_view s, size_t& pos, int n, int& out) {
  if (pos + n > s.size()) return false;
  out = 0;
  for (int i = 0; i < n; ++i) {
    const char c = s[pos + i];
    if (c < '0' || c > '9') return false;
    out = out * 10 + (c - '0');
  }
  pos += n;
  return true;
}

bool Expect(std::string_view s, size_t& pos, char a, char b = '\0') {
  if (pos >= s.size() || (s[pos] != a && (b == '\0' || s[pos] != b))) return false;
  ++pos;
  return true;
}

// NOAA's approximation of atmospheric refraction (degrees) at a geometric elevation (degrees).
double Refraction(double elevation) {
  if (elevation > 85.0) return 0.0;
  const double te = std::tan(elevation * kRadPerDeg);
  double arcsec;
  if (elevation > 5.0) {
    arcsec = 58.1 / te - 0.07 / (te * te * te) + 0.000086 / std::pow(te, 5);
  } else if (elevation > -0.575) {
    arcsec = 1735.0 + elevation * (-518.2 + elevation * (103.4 + elevation * (-12.79 + elevation * 0.711)));
  } else {
    arcsec = -20.772 / te;
  }
  return arcsec / 3600.0;
}

}  // namespace

StatusOr<double> ParseUtcTime(std::string_view s) {
  const std::string quoted = "\"" + std::string(s.substr(0, 64)) + "\"";
  const auto bad = [&](const char* why) {
    return InvalidArgument("time " + quoted + " is not ISO 8601 YYYY-MM-DDThh:mm:ss[.fff](Z|+hh:mm): " + why);
  };
  size_t pos = 0;
  int year, month, day, hour, minute, second;
  if (!Digits(s, pos, 4, year) || !Expect(s, pos, '-') || !Digits(s, pos, 2, month) || !Expect(s, pos, '-') ||
      !Digits(s, pos, 2, day)) {
    return bad("expected the date as YYYY-MM-DD");
  }
  if (!Expect(s, pos, 'T', 't') || !Digits(s, pos, 2, hour) || !Expect(s, pos, ':') ||
      !Digits(s, pos, 2, minute) || !Expect(s, pos, ':') || !Digits(s, pos, 2, second)) {
    return bad("expected the time of day as Thh:mm:ss");
  }
  if (month < 1 || month > 12 || day < 1 || day > DaysInMonth(year, month)) return bad("no such date");
  if (hour > 23 || minute > 59 || second > 59) return bad("hour, minute or second out of range");
  double fraction = 0;
  if (pos < s.size() && s[pos] == '.') {
    ++pos;
    double scale = 0.1;
    const size_t first = pos;
    while (pos < s.size() && s[pos] >= '0' && s[pos] <= '9' && pos - first < 9) {
      fraction += (s[pos] - '0') * scale;
      scale /= 10;
      ++pos;
    }
    if (pos == first) return bad("a decimal point needs digits after it");
  }
  int offset_minutes = 0;
  const bool utc = Expect(s, pos, 'Z', 'z');
  if (!utc && pos < s.size() && (s[pos] == '+' || s[pos] == '-')) {
    const int sign = s[pos++] == '-' ? -1 : 1;
    int oh, om;
    if (!Digits(s, pos, 2, oh) || !Expect(s, pos, ':') || !Digits(s, pos, 2, om)) {
      return bad("expected the zone offset as +hh:mm");
    }
    if (oh > 23 || om > 59) return bad("zone offset out of range");
    offset_minutes = sign * (oh * 60 + om);
  } else if (!utc) {
    return bad(pos == s.size() ? "no time zone (append Z for UTC or an offset like +02:00)"
                               : "unexpected characters");
  }
  if (pos != s.size()) return bad("unexpected characters after the zone");
  const int64_t seconds = DaysFromCivil(year, month, day) * 86400 + hour * 3600 + minute * 60 + second -
                          int64_t{offset_minutes} * 60;
  return static_cast<double>(seconds) + fraction;
}

StatusOr<SunPosition> SolarPosition(double unix_seconds, double latitude_deg, double longitude_deg) {
  if (!(latitude_deg >= -90.0 && latitude_deg <= 90.0)) {
    return InvalidArgument("latitude " + std::to_string(latitude_deg) + " is outside [-90, 90]");
  }
  if (!(longitude_deg >= -180.0 && longitude_deg <= 180.0)) {
    return InvalidArgument("longitude " + std::to_string(longitude_deg) + " is outside [-180, 180]");
  }
  if (!(unix_seconds >= kFirstValidUnix && unix_seconds < kEndValidUnix)) {
    return InvalidArgument("the solar position is computed for years 1901..2099 only");
  }
  const SolarEphemeris sun = SunEphemeris(JulianDayFromUnix(unix_seconds));
  const double utc_minutes = (unix_seconds - std::floor(unix_seconds / kSecondsPerDay) * kSecondsPerDay) / 60.0;
  // True solar time in minutes; the hour angle is 0 at local apparent noon, positive afternoons.
  const double true_solar_minutes = utc_minutes + sun.equation_of_time_min + 4.0 * longitude_deg;
  const double hour_angle = (true_solar_minutes / 4.0 - 180.0) * kRadPerDeg;
  const double lat = latitude_deg * kRadPerDeg;
  const double dec = sun.declination_deg * kRadPerDeg;
  const double cos_zenith = std::sin(lat) * std::sin(dec) + std::cos(lat) * std::cos(dec) * std::cos(hour_angle);
  const double elevation = 90.0 - std::acos(std::clamp(cos_zenith, -1.0, 1.0)) / kRadPerDeg;
  // Meeus (13.5), measured from the south; atan2 stays defined at the poles where NOAA's acos divides by 0.
  const double from_south =
      std::atan2(std::sin(hour_angle), std::cos(hour_angle) * std::sin(lat) - std::tan(dec) * std::cos(lat));
  double azimuth = std::fmod(from_south / kRadPerDeg + 180.0, 360.0);
  if (azimuth < 0) azimuth += 360.0;
  if (azimuth >= 360.0) azimuth -= 360.0;
  return SunPosition{azimuth, elevation + Refraction(elevation)};
}

Light SunLight(const SunPosition& sun) {
  const double az = sun.azimuth_deg * kRadPerDeg;
  const double el = sun.elevation_deg * kRadPerDeg;
  Light light;
  // Towards the sun is (sin az cos el, cos az cos el, sin el) in ENU; light travels the other way.
  light.travel = {-std::sin(az) * std::cos(el), -std::cos(az) * std::cos(el), -std::sin(el)};
  light.below_horizon = sun.elevation_deg <= 0.0;
  return light;
}

StatusOr<std::vector<Light>> SunLights(double from_unix_seconds, double until_unix_seconds, int samples,
                                       double latitude_deg, double longitude_deg) {
  if (samples < 1 || samples > kMaxSamples) {
    return InvalidArgument("samples must be in 1.." + std::to_string(kMaxSamples) + ", got " +
                           std::to_string(samples));
  }
  if (!(until_unix_seconds >= from_unix_seconds)) return InvalidArgument("the end time is before the start time");
  std::vector<Light> lights;
  lights.reserve(samples);
  for (int i = 0; i < samples; ++i) {
    const double t = samples == 1 ? from_unix_seconds
                                  : from_unix_seconds + (until_unix_seconds - from_unix_seconds) * i / (samples - 1);
    ASSIGN_OR_RETURN(SunPosition sun, SolarPosition(t, latitude_deg, longitude_deg));
    lights.push_back(SunLight(sun));
  }
  return lights;
}

}  // namespace pointdag
