// HTTP/1.1 transport (Boost.Beast over Asio, C++20 coroutines): keep-alive, uploads streamed to a
// file as they arrive (never held in memory), everything else handed to Service. The only file
// that includes Boost, so its slow headers compile once.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "service.h"

namespace pointdag::server {

class HttpServer {
 public:
  HttpServer(Service& service, Metrics& metrics, int threads);
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
