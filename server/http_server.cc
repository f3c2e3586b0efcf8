#include "http_server.h"

#include <sys/statvfs.h>

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <map>
#include <mutex>
#include <thread>

#include "http_request.h"

namespace pointdag::server {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

constexpr uint64_t kSmallBodyLimit = 1 << 20;
constexpr uint64_t kDrainLimit = 8 << 20;
constexpr size_t kBodyReadBytes = 64 << 10;  // what Beast reads in one call at most
constexpr auto kAcceptBackoff = std::chrono::milliseconds(100);
const std::string kUploadRoute = "/v1/datasets";

// A count that a connection or an upload holds while it lives; taking it fails at the cap.
class Slot {
 public:
  Slot() = default;
  Slot(Slot&& other) noexcept : count_(std::exchange(other.count_, nullptr)) {}
  Slot& operator=(Slot&&) = delete;
  ~Slot() {
    if (count_) count_->fetch_sub(1);
  }
  static std::optional<Slot> Take(std::atomic<int>& count, int cap) {
    if (count.fetch_add(1) >= cap) {
      count.fetch_sub(1);
      return std::nullopt;
    }
    Slot slot;
    slot.count_ = &count;
    return slot;
  }

 private:
  std::atomic<int>* count_ = nullptr;
};

// The upload's file is removed on every path out of the session — error, exception, closed
// connection — unless a job took it.
class UploadFile {
 public:
  explicit UploadFile(std::filesystem::path path) : path_(std::move(path)) {}
  UploadFile(const UploadFile&) = delete;
  UploadFile& operator=(const UploadFile&) = delete;
  ~UploadFile() {
    if (kept_) return;
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  const std::filesystem::path& path() const { return path_; }
  void Keep() { kept_ = true; }

 private:
  std::filesystem::path path_;
  bool kept_ = false;
};

bool OutOfSpace(const beast::error_code& ec) {
  return ec.category() == boost::system::system_category() && (ec.value() == ENOSPC || ec.value() == EDQUOT);
}

// The connection simply ended (closed, reset, timed out): nobody is left to answer.
bool ConnectionGone(const beast::error_code& ec) {
  return ec == http::error::end_of_stream || ec == asio::error::eof || ec == beast::error::timeout ||
         ec == asio::error::connection_reset || ec == asio::error::operation_aborted || ec == asio::error::broken_pipe;
}

// The client went away mid-request: there is nobody to answer (status 0 ends the session).
HttpResponse NoAnswer() {
  HttpResponse r;
  r.status = 0;
  return r;
}

// Over a connection cap the answer is written at once from the accept loop: a fresh socket's send
// buffer takes it whole, and the connection costs no session.
void RefuseConnection(tcp::socket& socket, const std::string& message) {
  const std::string body = "{\"error\": \"" + message + "\"}\n";
  const std::string answer = "HTTP/1.1 503 Service Unavailable\r\nServer: pointdagd/0.1\r\nContent-Type: application/json\r\n"
                             "Retry-After: 5\r\nConnection: close\r\nContent-Length: " + std::to_string(body.size()) +
                             "\r\n\r\n" + body;
  beast::error_code ec;
  socket.non_blocking(true, ec);
  socket.write_some(asio::buffer(answer), ec);
  socket.shutdown(tcp::socket::shutdown_both, ec);
  socket.close(ec);
}

}  // namespace

struct HttpServer::Impl {
  Service& service;
  Metrics& metrics;
  const HttpLimits limits;
  int threads;
  // Declared before `io`, so destroyed after it: a stop leaves sessions suspended in `io`, and
  // destroying their frames gives their connection slots back into these.
  std::atomic<int> connections{0}, uploads{0};
  std::mutex clients_mutex;
  std::map<asio::ip::address, int> per_client;
  asio::io_context io;
  tcp::acceptor acceptor{io};
  asio::thread_pool checks;  // uploads' checks (FinishUpload → OpenScan), never on an HTTP thread

  Impl(Service& s, Metrics& m, int t, const HttpLimits& l)
      : service(s), metrics(m), limits(l), threads(t), io(t), checks(static_cast<size_t>(l.check_threads)) {}

  // What one request-response exchange has done so far, for the session's last-resort answer.
  struct Exchange {
    bool response_started = false;
  };
  // A client's share of the connections, held for the connection's lifetime.
  class ClientSlot {
   public:
    ClientSlot(Impl& impl, asio::ip::address address) : impl_(&impl), address_(std::move(address)) {}
    ClientSlot(ClientSlot&& other) noexcept : impl_(std::exchange(other.impl_, nullptr)), address_(other.address_) {}
    ClientSlot& operator=(ClientSlot&&) = delete;
    ~ClientSlot() {
      if (!impl_) return;
      std::lock_guard lock(impl_->clients_mutex);
      if (--impl_->per_client[address_] == 0) impl_->per_client.erase(address_);
    }

   private:
    Impl* impl_;
    asio::ip::address address_;
  };
  std::optional<ClientSlot> TakeClientSlot(const asio::ip::address& address) {
    std::lock_guard lock(clients_mutex);
    int& count = per_client[address];
    if (count >= limits.max_connections_per_client) {
      if (count == 0) per_client.erase(address);
      return std::nullopt;
    }
    ++count;
    return ClientSlot(*this, address);
  }

  asio::awaitable<void> Accept();
  asio::awaitable<void> Session(tcp::socket socket, Slot connection, ClientSlot client);
  asio::awaitable<bool> Serve(beast::tcp_stream& stream, beast::flat_buffer& buffer, Exchange& exchange);
  asio::awaitable<bool> Respond(beast::tcp_stream& stream, const HttpRequest& request, HttpResponse response,
                                bool keep_alive, Clock::time_point start, Exchange& exchange);
  asio::awaitable<HttpResponse> ReadUpload(beast::tcp_stream& stream, beast::flat_buffer& buffer,
                                           http::request_parser<http::empty_body>& header_parser,
                                           const HttpRequest& request, bool& keep_alive);
  asio::awaitable<beast::error_code> ReadBodyAtMinimumRate(beast::tcp_stream& stream, beast::flat_buffer& buffer,
                                                           http::request_parser<http::file_body>& parser);
  std::optional<HttpResponse> CheckFreeSpace(std::optional<uint64_t> length) const;
  // The answer to a head that failed to parse or that CheckHead refuses (then the connection
  // closes); nullopt when it is fine, or when the connection is gone.
  std::optional<HttpResponse> RefuseHead(const beast::error_code& ec, const RequestHead& head) const;
};

asio::awaitable<void> HttpServer::Impl::Session(tcp::socket socket, Slot connection, ClientSlot client) {
  beast::tcp_stream stream(std::move(socket));
  beast::flat_buffer buffer;
  for (;;) {
    Exchange exchange;
    bool go_on = false;
    std::string failure;
    try {
      go_on = co_await Serve(stream, buffer, exchange);
    } catch (const std::exception& e) {
      failure = e.what();
    } catch (...) {
      failure = "an exception of unknown type";
    }
    if (failure.empty() && go_on) continue;
    if (!failure.empty()) {
      // No exception ends a session silently: logged, and answered while nothing of the response is out.
      spdlog::error("a request failed with an exception: {}", failure);
      if (!exchange.response_started) {
        try {
          HttpResponse error = service.Error(500, "internal error while serving this request; the daemon's log has the details", "other");
          const HttpRequest unknown;
          co_await Respond(stream, unknown, std::move(error), false, Clock::now(), exchange);
        } catch (const std::exception& e) {
          spdlog::error("the 500 answer failed too: {}", e.what());
        }
      }
    }
    break;
  }
  beast::error_code ec;
  stream.socket().shutdown(tcp::socket::shutdown_send, ec);
  // `connection` and `client` are held, not used: their counts drop as this frame ends.
  (void)connection;
  (void)client;
}

asio::awaitable<bool> HttpServer::Impl::Serve(beast::tcp_stream& stream, beast::flat_buffer& buffer, Exchange& exchange) {
  beast::error_code ec;
  if (buffer.size() == 0) {  // keep-alive: wait for the next request's first byte
    stream.expires_after(std::chrono::seconds(limits.idle_timeout_s));
    const size_t n = co_await stream.async_read_some(buffer.prepare(4096), asio::redirect_error(asio::use_awaitable, ec));
    if (ec) co_return false;
    buffer.commit(n);
  }
  stream.expires_after(std::chrono::seconds(limits.header_timeout_s));
  http::request_parser<http::empty_body> header_parser;
  header_parser.header_limit(limits.max_header_bytes);
  header_parser.body_limit(std::numeric_limits<std::uint64_t>::max());  // Beast checks Content-Length against it with the header; limits come per route
  co_await http::async_read_header(stream, buffer, header_parser, asio::redirect_error(asio::use_awaitable, ec));
  const auto start = Clock::now();
  // (No temporaries in a co_await's arguments in this file: GCC 12 may destroy them twice.)
  std::optional<HttpResponse> refusal = RefuseHead(ec, header_parser.get());
  if (ec && !refusal) co_return false;  // the connection ended or timed out: nobody to answer
  HttpRequest request;
  bool keep_alive = false;
  HttpResponse response;
  if (refusal) {
    response = std::move(*refusal);
  } else {
    request = ToRequest(header_parser.get());
    keep_alive = header_parser.get().keep_alive();
    if (service.IsUpload(request)) {
      response = co_await ReadUpload(stream, buffer, header_parser, request, keep_alive);
    } else {
      stream.expires_after(std::chrono::seconds(limits.body_timeout_s));
      http::request_parser<http::string_body> body_parser(std::move(header_parser));
      body_parser.body_limit(kSmallBodyLimit);
      co_await http::async_read(stream, buffer, body_parser, asio::redirect_error(asio::use_awaitable, ec));
      if (ec == http::error::body_limit) {
        response = service.Error(413, "request bodies here are at most 1 MiB", "other");
        keep_alive = false;
      } else if (ec) {
        co_return false;
      } else {
        request.body = std::move(body_parser.get().body());
        response = service.Handle(request);
      }
    }
  }
  if (response.status == 0) co_return false;  // the upload's client went away: nobody to answer
  const bool go_on = co_await Respond(stream, request, std::move(response), keep_alive, start, exchange);
  co_return go_on;
}

std::optional<HttpResponse> HttpServer::Impl::RefuseHead(const beast::error_code& ec, const RequestHead& head) const {
  if (ec == http::error::header_limit) {
    return service.Error(431, "the request header exceeds " + std::to_string(limits.max_header_bytes) + " bytes", "other");
  }
  if (ec && ConnectionGone(ec)) return std::nullopt;
  if (ec) return service.Error(400, "malformed request: " + ec.message(), "other");
  if (auto refusal = CheckHead(head, limits)) return service.Error(refusal->status, refusal->message, "other");
  return std::nullopt;
}

std::optional<HttpResponse> HttpServer::Impl::CheckFreeSpace(std::optional<uint64_t> length) const {
  struct statvfs disk {};
  if (::statvfs(service.config().upload_dir.c_str(), &disk) != 0) return std::nullopt;  // the open below reports it
  const uint64_t free_bytes = static_cast<uint64_t>(disk.f_bavail) * disk.f_frsize;
  const uint64_t needed = length.value_or(0) + limits.disk_reserve_bytes;
  if (needed <= free_bytes) return std::nullopt;
  return service.Error(507, "the daemon's disk is full: " + std::to_string(free_bytes) + " bytes free, the upload needs " +
                                std::to_string(length.value_or(0)) + " and " + std::to_string(limits.disk_reserve_bytes) +
                                " must stay free", kUploadRoute);
}

asio::awaitable<HttpResponse> HttpServer::Impl::ReadUpload(beast::tcp_stream& stream, beast::flat_buffer& buffer,
                                                           http::request_parser<http::empty_body>& header_parser,
                                                           const HttpRequest& request, bool& keep_alive) {
  beast::error_code ec;
  const auto length = header_parser.content_length();
  std::optional<HttpResponse> refusal = service.AdmitUpload(request);
  std::optional<Slot> upload_slot = refusal ? std::nullopt : Slot::Take(uploads, limits.max_uploads);
  if (!refusal) {
    if (!upload_slot) {
      refusal = service.Error(503, "the daemon takes " + std::to_string(limits.max_uploads) + " uploads at once; try again later", kUploadRoute);
      refusal->SetHeader("Retry-After", "30");
    }
  }
  if (!refusal) refusal = CheckFreeSpace(length ? std::optional<uint64_t>(*length) : std::nullopt);
  if (refusal) {
    // A small body is read and dropped so the client can read the answer and go on; a large
    // one (or one the client holds back for 100-continue) is refused by closing after the answer.
    if (length && *length <= kDrainLimit && request.Header("expect").empty()) {
      stream.expires_after(std::chrono::seconds(limits.body_timeout_s));
      http::request_parser<http::string_body> drain(std::move(header_parser));
      drain.body_limit(kDrainLimit);
      co_await http::async_read(stream, buffer, drain, asio::redirect_error(asio::use_awaitable, ec));
      if (ec) co_return NoAnswer();
    } else {
      keep_alive = false;
    }
    co_return std::move(*refusal);
  }
  if (request.Header("expect") == "100-continue") {
    stream.expires_after(std::chrono::seconds(limits.write_timeout_s));
    http::response<http::empty_body> go_on{http::status::continue_, 11};
    co_await http::async_write(stream, go_on, asio::redirect_error(asio::use_awaitable, ec));
    if (ec) co_return NoAnswer();
  }
  UploadFile file(service.config().upload_dir / (NewId() + ".upload"));
  http::request_parser<http::file_body> body_parser(std::move(header_parser));
  body_parser.body_limit(service.config().max_upload_bytes);
  body_parser.get().body().open(file.path().c_str(), beast::file_mode::write, ec);
  if (ec) {
    keep_alive = false;
    co_return service.Error(500, "cannot store the upload: " + ec.message(), kUploadRoute);
  }
  // Beast reads at most the buffer's spare capacity (up to 64 KiB) a call: left as the header made it,
  // a body came in ~4 KiB reads, five system calls each (13.7 MB: 3,450 reads, ~25 ms to the 202).
  buffer.reserve(buffer.size() + kBodyReadBytes);
  ec = co_await ReadBodyAtMinimumRate(stream, buffer, body_parser);
  body_parser.get().body().close();
  if (ec == http::error::body_limit) {
    keep_alive = false;
    co_return service.Error(413, "the upload exceeds " + std::to_string(service.config().max_upload_bytes) + " bytes", kUploadRoute);
  }
  if (OutOfSpace(ec)) {
    spdlog::warn("upload refused: the disk holding {} is full", file.path().parent_path().string());
    keep_alive = false;
    co_return service.Error(507, "the daemon's disk is full", kUploadRoute);
  }
  if (ec == beast::error::timeout) {
    spdlog::info("upload cut off: less than {} bytes in {} s", limits.upload_min_rate * static_cast<uint64_t>(limits.upload_rate_window_s),
                 limits.upload_rate_window_s);
    co_return NoAnswer();
  }
  if (ec && ConnectionGone(ec)) co_return NoAnswer();
  if (ec) {
    keep_alive = false;
    co_return service.Error(400, "malformed upload: " + ec.message(), kUploadRoute);
  }
  // The header check and the job's creation read the file and the store: on the check pool, so a
  // slow check never holds an HTTP thread.
  HttpResponse response = co_await asio::co_spawn(
      checks, [&]() -> asio::awaitable<HttpResponse> { co_return service.FinishUpload(request, file.path()); }, asio::use_awaitable);
  if (response.status == 202) file.Keep();  // its job owns the file now
  co_return response;
}

// Each successive upload_min_rate × window bytes must arrive within one window, so a client that
// trickles its body is cut off (the stream's deadline closes the connection) however long it is.
asio::awaitable<beast::error_code> HttpServer::Impl::ReadBodyAtMinimumRate(beast::tcp_stream& stream, beast::flat_buffer& buffer,
                                                                           http::request_parser<http::file_body>& parser) {
  const auto window = std::chrono::seconds(limits.upload_rate_window_s);
  const uint64_t quota = limits.upload_min_rate * static_cast<uint64_t>(limits.upload_rate_window_s);
  auto window_start = Clock::now();
  uint64_t in_window = 0;
  beast::error_code ec;
  while (!parser.is_done()) {
    stream.expires_at(window_start + window);
    in_window += co_await http::async_read_some(stream, buffer, parser, asio::redirect_error(asio::use_awaitable, ec));
    if (ec) co_return ec;
    if (in_window >= quota) {
      window_start = Clock::now();
      in_window = 0;
    }
  }
  co_return ec;
}

asio::awaitable<bool> HttpServer::Impl::Respond(beast::tcp_stream& stream, const HttpRequest& request, HttpResponse response,
                                                bool keep_alive, Clock::time_point start, Exchange& exchange) {
  const bool head = request.method == "HEAD";
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
  exchange.response_started = true;
  beast::error_code ec;
  stream.expires_after(std::chrono::seconds(limits.write_timeout_s));
  co_await http::async_write(stream, out, asio::redirect_error(asio::use_awaitable, ec));
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  metrics.CountRequest(response.route, response.status, seconds, head ? 0 : body_bytes);
  spdlog::debug("{} {} -> {} ({} bytes, {:.3f} ms)", request.method, request.target, response.status, body_bytes, seconds * 1e3);
  co_return !ec && keep_alive;
}

asio::awaitable<void> HttpServer::Impl::Accept() {
  asio::steady_timer backoff(io);
  bool failing = false;
  for (;;) {
    beast::error_code ec;
    // The socket takes the io_context's executor; each session runs on a strand of its own (below).
    tcp::socket socket = co_await acceptor.async_accept(asio::redirect_error(asio::use_awaitable, ec));
    if (ec) {
      if (!acceptor.is_open()) co_return;
      // Out of file descriptors (or another passing failure): retrying at once would spin a core
      // while nothing can change; the connections waiting in the backlog are taken once it passes.
      if (!failing) spdlog::warn("accept failed: {}; retrying every {} ms", ec.message(), kAcceptBackoff.count());
      failing = true;
      backoff.expires_after(kAcceptBackoff);
      co_await backoff.async_wait(asio::redirect_error(asio::use_awaitable, ec));
      continue;
    }
    failing = false;
    socket.set_option(tcp::no_delay(true), ec);
    const auto address = socket.remote_endpoint(ec).address();
    if (ec) continue;  // already gone
    auto connection = Slot::Take(connections, limits.max_connections);
    if (!connection) {
      RefuseConnection(socket, "the daemon serves " + std::to_string(limits.max_connections) + " connections at once; try again later");
      metrics.CountRequest("connection", 503, 0, 0);
      continue;
    }
    auto client = TakeClientSlot(address);
    if (!client) {
      RefuseConnection(socket, "too many connections from your address (at most " + std::to_string(limits.max_connections_per_client) + ")");
      metrics.CountRequest("connection", 503, 0, 0);
      continue;
    }
    asio::co_spawn(asio::make_strand(io), Session(std::move(socket), std::move(*connection), std::move(*client)), asio::detached);
  }
}

HttpServer::HttpServer(Service& service, Metrics& metrics, int threads, const HttpLimits& limits)
    : impl_(std::make_unique<Impl>(service, metrics, threads, limits)) {}
HttpServer::~HttpServer() { impl_->checks.join(); }

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
