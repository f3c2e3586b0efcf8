#include "http_server.h"

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <thread>

namespace pointdag::server {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;

struct HttpServer::Impl {
  Service& service;
  Metrics& metrics;
  int threads;
  asio::io_context io;
  tcp::acceptor acceptor{io};

  Impl(Service& s, Metrics& m, int t) : service(s), metrics(m), threads(t), io(t) {}
  asio::awaitable<void> Accept();
  asio::awaitable<void> Session(tcp::socket socket);
};

namespace {

constexpr auto kIdleTimeout = std::chrono::seconds(60);
constexpr auto kUploadTimeout = std::chrono::minutes(30);
constexpr uint64_t kSmallBodyLimit = 1 << 20;
constexpr uint64_t kDrainLimit = 8 << 20;

template <typename Fields>
HttpRequest ToRequest(const http::request_header<Fields>& header) {
  HttpRequest request;
  request.method = std::string(header.method_string());
  request.target = std::string(header.target());
  for (const auto& field : header) {
    std::string name(field.name_string());
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    request.headers[name] = std::string(field.value());
  }
  return request;
}

}  // namespace

asio::awaitable<void> HttpServer::Impl::Session(tcp::socket socket) {
  beast::tcp_stream stream(std::move(socket));
  beast::flat_buffer buffer;
  beast::error_code ec;
  for (;;) {
    stream.expires_after(kIdleTimeout);
    http::request_parser<http::empty_body> header_parser;
    header_parser.header_limit(16 * 1024);
    header_parser.body_limit(std::numeric_limits<std::uint64_t>::max());  // Beast checks Content-Length against it with the header; limits come per route
    co_await http::async_read_header(stream, buffer, header_parser, asio::redirect_error(asio::use_awaitable, ec));
    if (ec) {  // closed, timed out, or not HTTP: nothing to answer
      spdlog::debug("connection ends: {}", ec.message());
      break;
    }
    const auto start = std::chrono::steady_clock::now();
    HttpRequest request = ToRequest(header_parser.get());
    bool keep_alive = header_parser.get().keep_alive();
    const bool head = request.method == "HEAD";
    HttpResponse response;
    if (service.IsUpload(request)) {
      if (auto refusal = service.AdmitUpload(request)) {
        response = std::move(*refusal);
        // A small body is read and dropped so the client can read the answer and go on; a large
        // one (or one the client holds back for 100-continue) is refused by closing after the answer.
        const auto length = header_parser.content_length();
        if (length && *length <= kDrainLimit && request.Header("expect").empty()) {
          http::request_parser<http::string_body> drain(std::move(header_parser));
          drain.body_limit(kDrainLimit);
          co_await http::async_read(stream, buffer, drain, asio::redirect_error(asio::use_awaitable, ec));
          if (ec) break;
        } else {
          keep_alive = false;
        }
      } else {
        if (request.Header("expect") == "100-continue") {
          http::response<http::empty_body> go_on{http::status::continue_, 11};
          co_await http::async_write(stream, go_on, asio::redirect_error(asio::use_awaitable, ec));
          if (ec) break;
        }
        const auto file = service.config().upload_dir / (NewId() + ".upload");
        http::request_parser<http::file_body> body_parser(std::move(header_parser));
        body_parser.body_limit(service.config().max_upload_bytes);
        body_parser.get().body().open(file.c_str(), beast::file_mode::write, ec);
        if (ec) {
          response = service.Error(500, "cannot store the upload: " + ec.message(), "/v1/datasets");
          keep_alive = false;
        } else {
          stream.expires_after(kUploadTimeout);
          co_await http::async_read(stream, buffer, body_parser, asio::redirect_error(asio::use_awaitable, ec));
          body_parser.get().body().close();
          if (ec == http::error::body_limit) {
            std::filesystem::remove(file);
            response = service.Error(413, "the upload exceeds " + std::to_string(service.config().max_upload_bytes) + " bytes", "/v1/datasets");
            keep_alive = false;
          } else if (ec) {
            spdlog::debug("upload to {} ended: {}", file.string(), ec.message());
            std::filesystem::remove(file);  // the client went away mid-upload: nothing was made of it
            if (ec == http::error::end_of_stream || ec == asio::error::eof || ec == beast::error::timeout) break;
            response = service.Error(400, "malformed upload: " + ec.message(), "/v1/datasets");
            keep_alive = false;
          } else {
            response = service.FinishUpload(request, file);
          }
        }
      }
    } else {
      http::request_parser<http::string_body> body_parser(std::move(header_parser));
      body_parser.body_limit(kSmallBodyLimit);
      co_await http::async_read(stream, buffer, body_parser, asio::redirect_error(asio::use_awaitable, ec));
      if (ec == http::error::body_limit) {
        response = service.Error(413, "request bodies here are at most 1 MiB", "other");
        keep_alive = false;
      } else if (ec) {
        break;
      } else {
        request.body = std::move(body_parser.get().body());
        response = service.Handle(request);
      }
    }

    http::response<http::string_body> out{static_cast<http::status>(response.status), 11};
    out.set(http::field::server, "pointdagd/0.1");
    for (const auto& [name, value] : response.headers) out.insert(name, value);
    out.keep_alive(keep_alive);
    const size_t body_bytes = response.body.size();
    if (head) {
      out.set(http::field::content_length, std::to_string(body_bytes));
    } else {
      out.body() = std::move(response.body);
      if (response.status != 304 && response.status != 204) out.prepare_payload();
    }
    co_await http::async_write(stream, out, asio::redirect_error(asio::use_awaitable, ec));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    metrics.CountRequest(response.route, response.status, seconds, head ? 0 : body_bytes);
    spdlog::debug("{} {} -> {} ({} bytes, {:.3f} ms)", request.method, request.target, response.status, body_bytes, seconds * 1e3);
    if (ec || !keep_alive) break;
  }
  stream.socket().shutdown(tcp::socket::shutdown_send, ec);
}

asio::awaitable<void> HttpServer::Impl::Accept() {
  for (;;) {
    beast::error_code ec;
    tcp::socket socket = co_await acceptor.async_accept(asio::redirect_error(asio::use_awaitable, ec));
    if (ec) {
      if (!acceptor.is_open()) co_return;
      continue;
    }
    socket.set_option(tcp::no_delay(true), ec);
    asio::co_spawn(acceptor.get_executor(), Session(std::move(socket)), asio::detached);
  }
}

HttpServer::HttpServer(Service& service, Metrics& metrics, int threads)
    : impl_(std::make_unique<Impl>(service, metrics, threads)) {}
HttpServer::~HttpServer() = default;

StatusOr<uint16_t> HttpServer::Listen(const std::string& host, uint16_t port) {
  beast::error_code ec;
  const auto address = asio::ip::make_address(host, ec);
  if (ec) return InvalidArgument("cannot listen on '" + host + "': " + ec.message());
  const tcp::endpoint endpoint(address, port);
  impl_->acceptor.open(endpoint.protocol(), ec);
  if (!ec) impl_->acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) impl_->acceptor.bind(endpoint, ec);
  if (!ec) impl_->acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) return IoError("cannot listen on " + host + ":" + std::to_string(port) + ": " + ec.message());
  return impl_->acceptor.local_endpoint().port();
}

void HttpServer::Run() {
  asio::signal_set signals(impl_->io, SIGINT, SIGTERM);
  signals.async_wait([this](const beast::error_code&, int signal) {
    spdlog::info("signal {}: stopping", signal);
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->io.stop();
  });
  asio::co_spawn(impl_->io, impl_->Accept(), asio::detached);
  std::vector<std::thread> pool;
  for (int i = 1; i < impl_->threads; ++i) pool.emplace_back([this] { impl_->io.run(); });
  impl_->io.run();
  for (auto& t : pool) t.join();
}

}  // namespace pointdag::server
