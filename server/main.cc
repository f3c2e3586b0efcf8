// pointdagd: the daemon. Config from the embedded defaults, --config FILE, then flags.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>

#include "check.h"
#include "config.h"
#include "nightly.h"
#include "pointdag/gpu/stage_device.h"
#include "pointdag/ingest.h"
#include "pointdag/pipeline.h"
#include "http_server.h"
#include "jobs.h"
#include "startup.h"
#include "service.h"
#include "store.h"

using namespace pointdag;
using namespace pointdag::server;

namespace {

int Fail(int code, const Status& status) {
  std::fprintf(stderr, "pointdagd: %s\n", status.ToString().c_str());
  return code;
}

// The write token from the first source that has one: --token, --token-file, POINTDAGD_TOKEN,
// then the config's token_file and token.
Status ResolveTokens(DaemonConfig& config, const std::string& token_flag, const std::string& token_file_flag) {
  const char* env_token = std::getenv("POINTDAGD_TOKEN");
  if (!token_flag.empty()) {
    config.token = token_flag;
  } else if (!token_file_flag.empty()) {
    ASSIGN_OR_RETURN(config.token, ReadTokenFile(token_file_flag));
  } else if (env_token && *env_token) {
    config.token = env_token;
  } else if (!config.token_file.empty()) {
    ASSIGN_OR_RETURN(config.token, ReadTokenFile(config.token_file));
  }
  if (const char* env_read = std::getenv("POINTDAGD_READ_TOKEN"); env_read && *env_read) config.read_token = env_read;
  return Status::Ok();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pointdagd: upload scans over HTTP, serve tiled LOD SVDAGs"};
  std::string config_file, listen, data_dir, token, token_file, port_file;
  std::optional<std::string> web_dir;
  int workers = 0;
  bool check = false;
  bool no_token = false;
  app.add_option("--config", config_file, "TOML configuration (configs/pointdagd.toml)");
  app.add_option("--listen", listen, "HOST:PORT (port 0: any free port)");
  app.add_option("--data-dir", data_dir, "where the store, uploads and spill files live");
  app.add_option("--token", token, "bearer token required for writes (visible in ps: prefer --token-file or POINTDAGD_TOKEN)");
  app.add_option("--token-file", token_file, "read the write token from this file's first line");
  app.add_flag("--no-token", no_token, "allow listening beyond loopback without a token");
  app.add_option("--workers", workers, "concurrent ingest jobs")->check(CLI::Range(1, 64));
  app.add_option("--port-file", port_file, "write the bound port here once listening");
  app.add_option("--web-dir", web_dir, "the web viewer's files (build/web); \"\" serves no viewer");
  app.add_flag("--check", check, "check the store in --data-dir and exit: 0 consistent, 1 with a report");
  CLI11_PARSE(app, argc, argv);
  RetainFreedMemory();  // upload after upload reuses the heap

  DaemonConfig config;
  if (!config_file.empty()) {
    if (const Status s = LoadConfigFile(config_file, config); !s.ok()) return Fail(2, s);
  }
  if (!listen.empty()) {
    if (const Status s = ParseListen(listen, config); !s.ok()) return Fail(2, s);
  }
  if (!data_dir.empty()) config.data_dir = data_dir;
  if (workers > 0) config.workers = workers;
  if (!port_file.empty()) config.port_file = port_file;
  if (web_dir) config.web_dir = *web_dir;
  if (check) {
    const auto report = CheckDataDir(config.data_dir);
    if (!report.ok()) return Fail(1, report.status());
    std::printf("%s", report->ToString().c_str());
    return report->ok() ? 0 : 1;
  }
  if (const Status s = ResolveTokens(config, token, token_file); !s.ok()) return Fail(2, s);
  if (const Status s = CheckExposure(config, no_token); !s.ok()) return Fail(2, s);
  spdlog::set_level(spdlog::level::from_str(config.log_level));
  RaiseOpenFileLimit();

  std::error_code ec;
  std::filesystem::create_directories(config.data_dir / "uploads", ec);
  std::filesystem::create_directories(config.data_dir / "spill", ec);
  if (ec) {
    std::fprintf(stderr, "pointdagd: cannot create %s: %s\n", config.data_dir.c_str(), ec.message().c_str());
    return 1;
  }
  auto store = Store::Open(config.data_dir / "store.sqlite");
  if (!store.ok()) return Fail(1, store.status());
  if (const size_t swept = SweepLeftovers(**store, config.data_dir); swept > 0) {
    spdlog::info("swept {} file(s) a previous run left in uploads/ and spill/", swept);
  }
  // Where the heavy stages run (POINTDAG_DEVICE; under auto, the faster path measured now).
  if (const Status s = ChooseStageDevices(); !s.ok()) return Fail(2, s);
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
  limits.max_attempts = config.max_attempts;
  JobQueue jobs(**store, metrics, limits);
  ServiceConfig service_config;
  service_config.token = config.token;
  service_config.read_token = config.read_token;
  service_config.require_token_for_reads = config.require_token_for_reads;
  service_config.max_upload_bytes = config.max_upload_bytes;
  service_config.upload_dir = config.data_dir / "uploads";
  service_config.cors_origins = config.cors_origins;
  service_config.tile_cache_bytes = config.tile_cache_mb << 20;
  auto web = WebFiles::Load(config.web_dir);
  if (!web.ok()) {
    spdlog::warn("no web viewer: {} (build it with scripts/build, or set web_dir / --web-dir)", web.status().message());
    web = WebFiles();
  }
  service_config.web = std::make_shared<const WebFiles>(std::move(*web));
  service_config.tiles3d_cache_bytes = config.tiles3d_cache_mb << 20;
  if (config.nightly.reports_dir.empty()) config.nightly.reports_dir = config.data_dir / "reports";
  service_config.reports_dir = config.nightly.reports_dir;
  Service service(**store, jobs, metrics, service_config);
  HttpServer server(service, metrics, config.http_threads, config.http);
  auto port = server.Listen(config.host, config.port);
  if (!port.ok()) return Fail(1, port.status());
  jobs.Resume();
  std::optional<NightlyRunner> nightly;
  if (!config.nightly.corpus.empty()) {
    nightly.emplace(config.nightly, metrics);
    nightly->Start();
  }
  service.set_ready(true);
  if (!config.port_file.empty()) {
    const auto partial = config.port_file.string() + ".partial";
    std::ofstream(partial) << *port << "\n";
    std::filesystem::rename(partial, config.port_file, ec);
  }
  // Which tokens are set, never their values.
  const char* access = config.token.empty()              ? "no token"
                       : config.require_token_for_reads ? "token required for reads and writes"
                                                        : "token required for writes";
  spdlog::info("pointdagd listening on http://{}:{} (data in {}, {} worker(s), {}{})", config.host, *port,
               config.data_dir.string(), config.workers, access, config.read_token.empty() ? "" : ", read token set");
  if (service_config.web->enabled()) {
    spdlog::info("web viewer: http://{}:{}/ ({} files from {})", config.host, *port, service_config.web->file_count(),
                 config.web_dir.string());
  }
  server.Run();
  if (nightly) nightly->Stop();  // a running benchmark is sent SIGTERM: it leaves no report behind
  // A clean stop (SIGTERM, docker stop): no queued job starts now; the running ones get the grace
  // period to finish and commit.
  const size_t running = jobs.running();
  const auto unfinished = jobs.Drain(std::chrono::steady_clock::now() + std::chrono::seconds(config.shutdown_grace_s));
  if (!unfinished.empty()) {
    // An ingest cannot be cut short midway: it resumes from its upload on the next start (SQLite's
    // WAL makes leaving now as safe as a crash), and a clean stop is not counted as an attempt.
    for (const std::string& id : unfinished) {
      if (const Status s = (**store).ReturnAttempt(id); !s.ok()) spdlog::warn("job {}: {}", id, s.ToString());
    }
    spdlog::info("leaving with {} job(s) still running after the {} s grace period: they resume on the next start",
                 unfinished.size(), config.shutdown_grace_s);
    // A job that has just committed its dataset may not have removed its upload yet: leave no
    // orphan behind for `pointdagd --check` (the running ones' uploads and spill files stay).
    (void)SweepLeftovers(**store, config.data_dir, /*keep_spill=*/true);
    std::_Exit(0);
  }
  if (running > 0) spdlog::info("finished {} running job(s) before leaving", running);
  spdlog::info("stopped");
  return 0;
}
