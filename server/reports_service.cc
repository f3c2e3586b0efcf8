#include "reports_service.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "pointdag/bench/report.h"

namespace pointdag::server {
namespace {

bool IsReportId(const std::string& id) {
  if (id.size() != 16 || id[8] != 'T' || id[15] != 'Z') return false;
  for (size_t i = 0; i < 15; ++i) {
    if (i != 8 && (id[i] < '0' || id[i] > '9')) return false;
  }
  return true;
}

HttpResponse FileAnswer(const std::filesystem::path& file, const std::string& content_type, const std::string& route) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return FailAnswer(404, "no report " + file.stem().string().substr(7) + " (GET /v1/reports lists them)", route);
  std::ostringstream text;
  text << in.rdbuf();
  HttpResponse r;
  r.route = route;
  r.body = text.str();
  r.SetHeader("Content-Type", content_type);
  r.SetHeader("Cache-Control", "no-cache");
  return r;
}

}  // namespace

HttpResponse ReportsService::Get(const std::vector<std::string>& rest) const {
  if (rest.empty()) {
    nlohmann::json list = nlohmann::json::array();
    auto files = ListReports(dir_);
    std::reverse(files.begin(), files.end());
    for (const auto& file : files) {
      auto report = ReadReport(file);
      if (!report.ok()) continue;
      const std::string id = file.stem().string().substr(7);  // "report-" + id
      size_t failed = 0;
      for (const auto& c : (*report)["cases"]) failed += c.contains("error") ? 1 : 0;
      list.push_back({{"id", id},
                      {"created", report->value("created", nlohmann::json())},
                      {"json", "/v1/reports/" + id},
                      {"html", "/v1/reports/" + id + ".html"},
                      {"cases", (*report)["cases"].size()},
                      {"failed_cases", failed}});
    }
    return JsonAnswer(200, {{"reports", list}}, "/v1/reports");
  }
  const std::string route = "/v1/reports/{id}";
  std::string id = rest[0];
  const bool html = id.size() > 5 && id.ends_with(".html");
  if (html) id.resize(id.size() - 5);
  if (rest.size() != 1 || !IsReportId(id)) return FailAnswer(400, "a report is addressed as /v1/reports/YYYYMMDDTHHMMSSZ[.html]", route);
  return html ? FileAnswer(dir_ / ("report-" + id + ".html"), "text/html; charset=utf-8", route)
              : FileAnswer(dir_ / ("report-" + id + ".json"), "application/json", route);
}

HttpResponse ReportsService::Latest() const {
  const auto files = ListReports(dir_);
  if (files.empty()) return FailAnswer(404, "no benchmark report yet (the [nightly] schedule writes them)", "/reports/latest.html");
  HttpResponse r = FileAnswer(std::filesystem::path(files.back()).replace_extension(".html"), "text/html; charset=utf-8", "/reports/latest.html");
  r.SetHeader("Cache-Control", "no-store");
  return r;
}

}  // namespace pointdag::server
