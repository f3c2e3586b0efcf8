// pointdagd: the daemon. Config from the embedded defaults, --config FILE, then flags.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>

#include "check.h"
#include "config.h"
#include "pointdag/gpu/stage_device.h"
#include "pointdag/pipeline.h"
#include "http_server.h"
#include "jobs.h"
#include "service.h"
#include "store.h"

using namespace pointdag;
using namespace pointdag::server;

int main(int argc, char** argv) {
  CLI::App app{"pointdagd: upload scans over HTTP, serve tiled LOD SVDAGs"};
  std::string config_file, listen, data_dir, token, port_file;
  int workers = 0;
  bool check = false;
  app.add_option("--config", config_file, "TOML configuration (configs/pointdagd.toml)");
  app.add_option("--listen", listen, "HOST:PORT (port 0: any free port)");
  app.add_option("--data-dir", data_dir, "where the store, uploads and spill files live");
  app.add_option("--token", token, "bearer token required for writes");
  app.add_option("--workers", workers, "concurrent ingest jobs")->check(CLI::Range(1, 64));
  app.add_option("--port-file", port_file, "write the bound port here once listening");
  app.add_flag("--check", check, "check the store in --data-dir and exit: 0 consistent, 1 with a report");
  CLI11_PARSE(app, argc, argv);

  DaemonConfig config;
  if (!config_file.empty()) {
    if (const Status s = LoadConfigFile(config_file, config); !s.ok()) {
      std::fprintf(stderr, "pointdagd: %s\n", s.ToString().c_str());
      return 2;
    }
  }
  if (!listen.empty()) {
    if (const Status s = ParseListen(listen, config); !s.ok()) {
      std::fprintf(stderr, "pointdagd: %s\n", s.ToString().c_str());
      return 2;
    }
  }
  if (!data_dir.empty()) config.data_dir = data_dir;
  if (!token.empty()) config.token = token;
  if (workers > 0) config.workers = workers;
  if (!port_file.empty()) config.port_file = port_file;
  spdlog::set_level(spdlog::level::from_str(config.log_level));
  if (check) {
    const auto report = CheckDataDir(config.data_dir);
    if (!report.ok()) std::fprintf(stderr, "pointdagd: %s\n", report.status().ToString().c_str());
    if (report.ok()) std::printf("%s", report->ToString().c_str());
    return report.ok() && report->ok() ? 0 : 1;
  }

  std::error_code ec;
  std::filesystem::create_directories(config.data_dir / "uploads", ec);
  std::filesystem::create_directories(config.data_dir / "spill", ec);
  if (ec) {
    std::fprintf(stderr, "pointdagd: cannot create %s: %s\n", config.data_dir.c_str(), ec.message().c_str());
    return 1;
  }
  auto store = Store::Open(config.data_dir / "store.sqlite");
  if (!store.ok()) {
    std::fprintf(stderr, "pointdagd: %s\n", store.status().ToString().c_str());
    return 1;
  }
  // Where the heavy stages run (POINTDAG_DEVICE; under auto, the faster path measured now).
  if (const Status s = ChooseStageDevices(); !s.ok()) {
    std::fprintf(stderr, "pointdagd: %s\n", s.ToString().c_str());
    return 2;
  }
  spdlog::info("stages: {}", gpu::DescribeDevices());
  Metrics metrics;
  std::vector<Metrics::StageDevice> stages;
  for (const gpu::StageChoice& c : gpu::StageChoices()) {
    stages.push_back({gpu::StageName(c.stage), c.vulkan ? c.device : "cpu", c.timing.cpu_seconds, c.timing.vulkan_seconds});
  }
  metrics.SetStageDevices(std::move(stages));
  JobLimits limits;
  limits.workers = config.workers;
  limits.capacity = config.queue_size;
  limits.spill_dir = config.data_dir / "spill";
  limits.upload_dir = config.data_dir / "uploads";
  JobQueue jobs(**store, metrics, limits);
  ServiceConfig service_config;
  service_config.token = config.token;
  service_config.max_upload_bytes = config.max_upload_bytes;
  service_config.upload_dir = config.data_dir / "uploads";
  service_config.cors_origins = {config.cors_origin};
  service_config.tile_cache_bytes = config.tile_cache_mb << 20;
  Service service(**store, jobs, metrics, service_config);
  HttpServer server(service, metrics, config.http_threads);
  auto port = server.Listen(config.host, config.port);
  if (!port.ok()) {
    std::fprintf(stderr, "pointdagd: %s\n", port.status().ToString().c_str());
    return 1;
  }
  jobs.Resume();
  service.set_ready(true);
  if (!config.port_file.empty()) {
    const auto partial = config.port_file.string() + ".partial";
    std::ofstream(partial) << *port << "\n";
    std::filesystem::rename(partial, config.port_file, ec);
  }
  spdlog::info("pointdagd listening on http://{}:{} (data in {}, {} worker(s){})", config.host, *port,
               config.data_dir.string(), config.workers, config.token.empty() ? ", no token" : ", token required for writes");
  server.Run();
  if (jobs.running() > 0) {
    // An ingest cannot be interrupted midway; its job resumes from the upload on the next start,
    // and SQLite's WAL makes leaving now as safe as a crash.
    spdlog::info("leaving with {} job(s) running: they resume on the next start", jobs.running());
    std::_Exit(0);
  }
  return 0;
}
