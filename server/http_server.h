// HTTP/1.1 transport (Boost.Beast over Asio, C++20 coroutines): keep-alive, uploads streamed to a
// file as they arrive (never held in memory) and checked on a small pool off the HTTP threads,
// everything else handed to Service. Every phase of a connection has a deadline and every
// resource a cap (HttpLimits). With http_request.cc, the only files that include Boost.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "config.h"
#include "service.h"

namespace pointdag::server {

class HttpServer {
 public:
  HttpServer(Service& service, Metrics& metrics, int threads, const HttpLimits& limits);
  ~HttpServer();
  // Binds and listens; returns the bound port (useful with port 0).
  StatusOr<uint16_t> Listen(const std::string& host, uint16_t port);
  // Serves until SIGINT/SIGTERM.
  void Run();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pointdag::server
