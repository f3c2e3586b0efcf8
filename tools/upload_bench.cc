// `pointdag bench --server URL`: goal 5's daemon ingest as a user meets it. Each scan is uploaded
// twice to a running pointdagd (POST /v1/datasets, the file streamed from disk over one keep-alive
// connection); the second upload is the figure (the first pays the process's first use of the
// scan's CRS). End to end runs from the upload's first byte to the job's `updated` time once it is
// `done` (its dataset stored and served): the daemon's own clock, so the polling (every 20 ms) adds
// nothing to it and takes little CPU from the ingest.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "bench.h"
#include "client.h"
#include "pointdag/bench/report.h"

namespace pointdag {
namespace {

double UnixNow() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

struct Upload {
  double accepted_s = 0;  // until the 202 (the body received and written)
  double total_s = 0;     // until the job was done
  nlohmann::json job;
  nlohmann::json dataset;
};

StatusOr<Upload> UploadOnce(client::Connection& connection, const std::filesystem::path& scan, const std::string& token) {
  std::string target = "/v1/datasets?name=" + scan.stem().string();
  if (const auto epsg = CrsOverride(scan.filename().string())) target += "&epsg=" + std::to_string(*epsg);
  std::map<std::string, std::string> headers;
  if (!token.empty()) headers["Authorization"] = "Bearer " + token;
  Upload out;
  const double start = UnixNow();
  ASSIGN_OR_RETURN(const client::Response accepted, connection.Upload(target, scan, headers));
  out.accepted_s = UnixNow() - start;
  if (accepted.status != 202) return IoError("the upload of " + scan.filename().string() + " got " + std::to_string(accepted.status) + ": " + accepted.body);
  const std::string job_target = accepted.Header("location");
  for (;;) {
    ASSIGN_OR_RETURN(const client::Response r, client::GetOk(connection, job_target));
    out.job = nlohmann::json::parse(r.body, nullptr, false);
    const std::string status = out.job.is_object() ? out.job.value("status", "") : "";
    if (status == "failed") return IoError("the job of " + scan.filename().string() + " failed: " + out.job.value("error", ""));
    if (status == "done") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  out.total_s = out.job.value("updated", start) - start;
  ASSIGN_OR_RETURN(const client::Response d, client::GetOk(connection, "/v1/datasets/" + out.job.value("dataset_id", "")));
  out.dataset = nlohmann::json::parse(d.body, nullptr, false);
  // Uploads of the same file should not pile up in the daemon's store.
  ASSIGN_OR_RETURN(const client::Response gone, connection.Request("DELETE", "/v1/datasets/" + out.job.value("dataset_id", ""), headers));
  if (gone.status != 204) return IoError("deleting the benchmark's dataset got " + std::to_string(gone.status));
  return out;
}

}  // namespace

int RunUploadBench(const BenchOptions& options) {
  auto url = client::ParseUrl(options.server);
  if (!url.ok()) {
    std::fprintf(stderr, "%s\n", url.status().ToString().c_str());
    return 2;
  }
  const char* token = std::getenv("POINTDAGD_TOKEN");
  auto connection = client::Connection::Open(url->host, url->port);
  if (!connection.ok()) {
    std::fprintf(stderr, "%s\n", connection.status().ToString().c_str());
    return 1;
  }
  if (!options.json) {
    std::printf("machine: %s; each scan uploaded twice to pointdagd at %s (POST /v1/datasets, derived voxel, 38 dB);\n"
                "the second: seconds until the 202, until the job was done (end to end), M points/s end to end, the\n"
                "daemon's ingest_seconds.total; the first upload's end to end\n",
                MachineName().c_str(), options.server.c_str());
    std::printf("| scan | points | voxel | upload s (to 202) | end to end s | M points/s | ingest s (daemon) | first upload s |\n"
                "|---|---|---|---|---|---|---|---|\n");
  }
  int failures = 0;
  for (const auto& scan : ScansIn(options.data_dir)) {
    auto first = UploadOnce(**connection, scan, token ? token : "");
    auto second = first.ok() ? UploadOnce(**connection, scan, token ? token : "") : first;
    if (!second.ok()) {
      std::fprintf(stderr, "%s: %s\n", scan.filename().c_str(), second.status().ToString().c_str());
      ++failures;
      continue;
    }
    const double points = second->job.value("points_in", 0.0);
    nlohmann::json r = {{"scan", scan.filename().string()},
                        {"points", points},
                        {"voxel", second->dataset.value("voxel_size", 0.0)},
                        {"upload_s", second->accepted_s},
                        {"end_to_end_s", second->total_s},
                        {"points_per_s", points / second->total_s},
                        {"daemon_ingest_s", second->dataset["ingest_seconds"].value("total", 0.0)},
                        {"first_end_to_end_s", first->total_s}};
    if (options.json) {
      std::cout << r.dump() << std::endl;
      continue;
    }
    std::printf("| %s | %.0f | %g | %.3f | %.3f | %.2f | %.3f | %.3f |\n", scan.filename().c_str(), points,
                r["voxel"].get<double>(), second->accepted_s, second->total_s, points / second->total_s / 1e6,
                r["daemon_ingest_s"].get<double>(), first->total_s);
  }
  return failures ? 1 : 0;
}

}  // namespace pointdag
