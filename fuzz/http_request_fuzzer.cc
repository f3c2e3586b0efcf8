// Raw bytes as a client would send them, through the server's own path: Beast's request parser
// with the daemon's limits, the transport's head checks and conversion (http_request.h), then
// Service::AdmitUpload for uploads or Service::Handle for everything else, over a real Store in a
// temporary folder (made once per process).
#include <boost/beast/http.hpp>

#include <cstdint>
#include <cstdlib>
#include <filesystem>

#include "http_request.h"
#include "jobs.h"
#include "metrics.h"
#include "service.h"
#include "store.h"

namespace {

using namespace pointdag::server;
namespace http = boost::beast::http;

struct World {
  std::filesystem::path dir;
  std::unique_ptr<Store> store;
  Metrics metrics;
  std::unique_ptr<JobQueue> jobs;
  std::unique_ptr<Service> service;
  HttpLimits limits;

  World() {
    char name[] = "/tmp/pointdag-fuzz-http-XXXXXX";
    if (!mkdtemp(name)) std::abort();
    dir = name;
    std::filesystem::create_directories(dir / "uploads");
    auto opened = Store::Open(dir / "store.sqlite");
    if (!opened.ok()) std::abort();
    store = std::move(*opened);
    JobLimits job_limits;
    job_limits.spill_dir = dir / "spill";
    jobs = std::make_unique<JobQueue>(*store, metrics, job_limits);
    ServiceConfig config;
    config.token = "fuzz-token";
    config.read_token = "fuzz-read";
    config.upload_dir = dir / "uploads";
    service = std::make_unique<Service>(*store, *jobs, metrics, config);
    service->set_ready(true);
  }
};

World& TheWorld() {
  static World* world = new World();  // never destroyed: the fuzzer exits without unwinding
  return *world;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  World& world = TheWorld();
  http::request_parser<http::string_body> parser;
  parser.header_limit(world.limits.max_header_bytes);
  parser.body_limit(1 << 20);
  parser.eager(true);
  boost::beast::error_code ec;
  boost::asio::const_buffer input(data, size);
  while (input.size() > 0 && !parser.is_done()) {
    const size_t used = parser.put(input, ec);
    input += used;
    if (ec == http::error::need_more) {
      ec = {};
      break;
    }
    if (ec || used == 0) break;
  }
  if (!ec && !parser.is_done() && parser.is_header_done()) parser.put_eof(ec);
  if (!parser.is_header_done()) return 0;
  if (CheckHead(parser.get().base(), world.limits)) return 0;
  HttpRequest request = ToRequest(parser.get().base());
  if (world.service->IsUpload(request)) {
    (void)world.service->AdmitUpload(request);
    return 0;
  }
  if (ec || !parser.is_done()) return 0;
  request.body = parser.get().body();
  (void)world.service->Handle(request);
  return 0;
}
