#include "pointdag/bench/report_html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "pointdag/bench/corpus_case.h"

namespace pointdag {
namespace {

std::string Escape(const std::string& text) {
  std::string out;
  for (char ch : text) {
    switch (ch) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += ch;
    }
  }
  return out;
}

std::string Text(const nlohmann::json& object, const char* key) {
  const auto it = object.find(key);
  if (it == object.end()) return "";
  return Escape(it->is_string() ? it->get<std::string>() : it->dump());
}


std::string Fixed(double v, int digits) {
  if (!std::isfinite(v)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// A plot area of kWidth x kHeight with margins; x and y map data ranges onto it.
constexpr double kWidth = 420, kHeight = 260, kLeft = 48, kBottom = 32, kTop = 12, kRight = 12;

struct Axes {
  double x0, x1, y0, y1;
  double X(double x) const { return kLeft + (x - x0) / (x1 - x0) * (kWidth - kLeft - kRight); }
  double Y(double y) const { return kHeight - kBottom - (y - y0) / (y1 - y0) * (kHeight - kBottom - kTop); }
};

std::string Frame(const Axes& a, const char* x_label, const char* y_label) {
  std::string s;
  char buf[256];
  std::snprintf(buf, sizeof(buf), "<rect x='%g' y='%g' width='%g' height='%g' fill='none' stroke='#888'/>", kLeft, kTop,
                kWidth - kLeft - kRight, kHeight - kBottom - kTop);
  s += buf;
  for (int i = 0; i <= 4; ++i) {
    const double x = a.x0 + (a.x1 - a.x0) * i / 4, y = a.y0 + (a.y1 - a.y0) * i / 4;
    std::snprintf(buf, sizeof(buf), "<text x='%g' y='%g' class='tick' text-anchor='middle'>%.3g</text>", a.X(x), kHeight - kBottom + 13, x);
    s += buf;
    std::snprintf(buf, sizeof(buf), "<text x='%g' y='%g' class='tick' text-anchor='end'>%.3g</text>", kLeft - 4, a.Y(y) + 4, y);
    s += buf;
  }
  std::snprintf(buf, sizeof(buf),
                "<text x='%g' y='%g' class='label' text-anchor='middle'>%s</text>"
                "<text x='12' y='%g' class='label' text-anchor='middle' transform='rotate(-90 12 %g)'>%s</text>",
                (kLeft + kWidth - kRight) / 2, kHeight - 4, x_label, kHeight / 2, kHeight / 2, y_label);
  return s + buf;
}

std::string Polyline(const Axes& a, const std::vector<std::pair<double, double>>& points, const char* color, const std::string& name) {
  std::string path, dots;
  char buf[160];
  for (const auto& [x, y] : points) {
    std::snprintf(buf, sizeof(buf), "%g,%g ", a.X(x), a.Y(y));
    path += buf;
    std::snprintf(buf, sizeof(buf), "<circle cx='%g' cy='%g' r='3' fill='%s'><title>%s %.3f</title></circle>", a.X(x), a.Y(y), color,
                  Escape(name).c_str(), y);
    dots += buf;
  }
  return "<polyline fill='none' stroke='" + std::string(color) + "' stroke-width='1.5' points='" + path + "'/>" + dots;
}

std::string Level(const Axes& a, double y, const char* color, const std::string& name) {
  if (!std::isfinite(y)) return "";
  char buf[320];
  std::snprintf(buf, sizeof(buf),
                "<line x1='%g' x2='%g' y1='%g' y2='%g' stroke='%s' stroke-dasharray='5 3'/><text x='%g' y='%g' class='tick' fill='%s'>%s %.2f</text>",
                kLeft, kWidth - kRight, a.Y(y), a.Y(y), color, kLeft + 4, a.Y(y) - 3, color, Escape(name).c_str(), y);
  return buf;
}

const std::map<std::string, const char*> kColors = {
    {"vbr", "#1f77b4"}, {"fixed3", "#9467bd"}, {"hierarchical", "#8c564b"}, {"image", "#ff7f0e"}};

std::string RateDistortionSvg(const nlohmann::json& c) {
  std::map<std::string, std::vector<std::pair<double, double>>> curves;
  double lossless = NAN, x0 = INFINITY, x1 = -INFINITY, y1 = JsonNumber(c, "draco_bits_per_point");
  for (const auto& row : c.value("ours", nlohmann::json::array())) {
    const std::string codec = row.value("codec", "");
    const double bits = JsonNumber(row, "bits_per_point"), psnr = JsonNumber(row, "psnr_y");
    if (codec == "lossless") lossless = bits;
    if (!std::isfinite(psnr) || !kColors.count(codec)) continue;
    curves[codec].push_back({psnr, bits});
    x0 = std::min(x0, psnr), x1 = std::max(x1, psnr), y1 = std::max(y1, bits);
  }
  if (std::isfinite(lossless)) y1 = std::max(y1, lossless);
  if (!std::isfinite(x0) || !std::isfinite(y1)) return "<p>no lossy codec reached a target</p>";
  const Axes a{std::floor(x0 - 1), std::ceil(x1 + 1), 0, y1 * 1.08};
  std::string svg = "<svg viewBox='0 0 420 260' width='420' height='260' role='img'>" + Frame(a, "PSNR-Y (dB)", "bits per point");
  for (auto& [codec, points] : curves) {
    std::sort(points.begin(), points.end());
    svg += Polyline(a, points, kColors.at(codec), codec);
  }
  svg += Level(a, lossless, "#2ca02c", "ours lossless");
  svg += Level(a, JsonNumber(c, "draco_bits_per_point"), "#d62728", "Draco lossless");
  return svg + "</svg>";
}

// Bits per point of `key` ("vbr@38", "lossless") of the case (scan, voxel) in each report.
std::vector<std::pair<double, double>> Trend(const std::vector<const nlohmann::json*>& reports, const nlohmann::json& c, const std::string& key) {
  std::vector<std::pair<double, double>> out;
  for (size_t i = 0; i < reports.size(); ++i) {
    for (const auto& other : reports[i]->value("cases", nlohmann::json::array())) {
      if (other.value("scan", "") != c.value("scan", "") || JsonNumber(other, "voxel") != JsonNumber(c, "voxel")) continue;
      for (const auto& row : other.value("ours", nlohmann::json::array())) {
        if (CodecRowKey(row) == key && std::isfinite(JsonNumber(row, "bits_per_point"))) out.push_back({double(i), JsonNumber(row, "bits_per_point")});
      }
    }
  }
  return out;
}

std::string TrendSvg(const std::vector<const nlohmann::json*>& reports, const nlohmann::json& c) {
  const std::vector<std::string> keys = {"vbr@38", "lossless"};
  const char* colors[] = {"#1f77b4", "#2ca02c"};
  double y1 = 0;
  std::vector<std::vector<std::pair<double, double>>> series;
  for (const auto& key : keys) {
    series.push_back(Trend(reports, c, key));
    for (const auto& p : series.back()) y1 = std::max(y1, p.second);
  }
  if (y1 <= 0) return "";
  const Axes a{0, std::max(1.0, double(reports.size() - 1)), 0, y1 * 1.15};
  std::string svg = "<svg viewBox='0 0 420 260' width='420' height='260' role='img'>" + Frame(a, "report (oldest to this one)", "bits per point");
  for (size_t k = 0; k < keys.size(); ++k) svg += Polyline(a, series[k], colors[k], keys[k]);
  return svg + "</svg>";
}

}  // namespace

std::string ReportHtml(const nlohmann::json& report, const std::vector<nlohmann::json>& history) {
  std::vector<const nlohmann::json*> reports;
  for (const auto& r : history) reports.push_back(&r);
  reports.push_back(&report);
  const nlohmann::json machine = report.value("machine", nlohmann::json::object());
  const nlohmann::json versions = report.value("versions", nlohmann::json::object());
  std::string h =
      "<!doctype html><html lang='en'><head><meta charset='utf-8'><title>pointdag benchmark " + Text(report, "id") +
      "</title><style>body{font:14px system-ui,sans-serif;margin:2em;color:#222}table{border-collapse:collapse;margin:1em 0}"
      "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f4f4f4}td:first-child{text-align:left}"
      ".tick{font-size:10px;fill:#555}.label{font-size:11px}.plots{display:flex;gap:1em;flex-wrap:wrap}</style></head><body>";
  h += "<h1>pointdag compression benchmark</h1><p>Report <b>" + Text(report, "id") + "</b>, " + Text(report, "created") +
       ". Machine: " + Text(machine, "cpu") + ". pointdag " + Text(versions, "pointdag") + ", libdraco " + Text(versions, "draco") +
       ". Corpus: " + Text(report, "corpus") + ".</p><p>Settings: <code>" + Text(report, "settings") + "</code></p>";
  h += "<table><tr><th>scan</th><th>voxel</th><th>voxels</th><th>geometry b/vox</th><th>VBR@38 b/pt</th><th>lossless b/pt</th>"
       "<th>Draco b/pt</th><th>lossless / Draco</th><th>encode Mvox/s ours / Draco</th><th>decode Mvox/s ours / Draco</th>"
       "<th>peak RSS MiB</th></tr>";
  for (const auto& c : report.value("cases", nlohmann::json::array())) {
    if (c.contains("error")) {
      h += "<tr><td>" + Text(c, "scan") + "</td><td colspan='10'>error: " + Text(c, "error") + "</td></tr>";
      continue;
    }
    double vbr38 = NAN, lossless = NAN;
    for (const auto& row : c.value("ours", nlohmann::json::array())) {
      if (CodecRowKey(row) == "vbr@38") vbr38 = JsonNumber(row, "bits_per_point");
      if (CodecRowKey(row) == "lossless") lossless = JsonNumber(row, "bits_per_point");
    }
    const nlohmann::json speed = c.value("speed", nlohmann::json::object());
    const double draco = JsonNumber(c, "draco_bits_per_point");
    h += "<tr><td>" + Text(c, "scan") + "</td><td>" + Text(c, "voxel") + "</td><td>" + Text(c, "voxels") + "</td><td>" +
         Fixed(JsonNumber(c, "geometry_bits_per_voxel"), 3) + "</td><td>" + Fixed(vbr38, 3) + "</td><td>" + Fixed(lossless, 3) + "</td><td>" +
         Fixed(draco, 3) + "</td><td>" + Fixed(lossless / draco, 3) + "</td><td>" +
         Fixed(JsonNumber(speed, "ours_encode_points_per_second") / 1e6, 2) + " / " + Fixed(JsonNumber(speed, "draco_encode_points_per_second") / 1e6, 2) +
         "</td><td>" + Fixed(JsonNumber(speed, "ours_decode_points_per_second") / 1e6, 2) + " / " +
         Fixed(JsonNumber(speed, "draco_decode_points_per_second") / 1e6, 2) + "</td><td>" + Fixed(JsonNumber(c, "peak_rss_bytes") / 1048576.0, 0) +
         "</td></tr>";
  }
  h += "</table><p>Plots: <b style='color:#1f77b4'>VBR</b>, <b style='color:#9467bd'>fixed3</b>, <b style='color:#8c564b'>"
       "hierarchical</b>, <b style='color:#ff7f0e'>best "
       "image mapping</b> (bits per point against PSNR-Y); dashed, the lossless totals: <b style='color:#2ca02c'>ours</b> and "
       "<b style='color:#d62728'>Draco's</b>. Trends: VBR at 38 dB (blue) and lossless (green) over the reports in this folder.</p>";
  for (const auto& c : report.value("cases", nlohmann::json::array())) {
    if (c.contains("error")) continue;
    h += "<h2>" + Text(c, "scan") + ", voxel " + Text(c, "voxel") + "</h2><div class='plots'>" + RateDistortionSvg(c) + TrendSvg(reports, c) + "</div>";
  }
  return h + "</body></html>\n";
}

}  // namespace pointdag
