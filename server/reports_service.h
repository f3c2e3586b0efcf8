// The nightly benchmark's reports (docs/nightly.md), served from the reports folder:
//   GET /v1/reports                 {"reports": [{"id", "created", "json", "html", "cases", "failed_cases"}]}, newest first
//   GET /v1/reports/{id}            the report.json (application/json)
//   GET /v1/reports/{id}.html       the report.html (text/html)
//   GET /reports/latest.html        the newest report.html
// 400 for an id that is not a report id (YYYYMMDDTHHMMSSZ: nothing else can name a file), 404 for
// a report that is not there. Method and token checks are the caller's (Service::Route).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "answers.h"

namespace pointdag::server {

class ReportsService {
 public:
  explicit ReportsService(std::filesystem::path dir) : dir_(std::move(dir)) {}

  // `rest`: the path's parts after "/v1/reports" (empty: the list).
  HttpResponse Get(const std::vector<std::string>& rest) const;
  HttpResponse Latest() const;

 private:
  std::filesystem::path dir_;
};

}  // namespace pointdag::server
