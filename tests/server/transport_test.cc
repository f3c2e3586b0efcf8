// pointdagd's transport against hostile and careless clients: framing, limits, caps, deadlines,
// uploads that fail midway. A real daemon on loopback per test, configured small so every limit
// is reached in a moment; raw sockets where the HTTP client would not misbehave.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "daemon_util.h"
#include "test_util.h"

namespace pointdag {
namespace {

using client::Response;

std::filesystem::path TinyLas() { return testing::DataDir() / "tiny_1.2-with-color_1065pts.las"; }

// A daemon in its own scratch folder with `toml` as its config.
std::unique_ptr<Daemon> StartDaemon(const testing::ScratchDir& scratch, const std::string& toml,
                                    const std::function<void(Daemon&)>& prepare = {}) {
  std::ofstream(scratch / "pointdagd.toml") << toml;
  auto daemon = std::make_unique<Daemon>(scratch.path(), std::vector<std::string>{"--config", (scratch / "pointdagd.toml").string()});
  if (prepare) prepare(*daemon);
  (void)daemon->Start();  // a failure is recorded; callers ASSERT started()
  return daemon;
}

size_t Uploads(const Daemon& daemon) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(daemon.var() / "uploads")) ++n;
  return n;
}

std::string Request(const std::string& method, const std::string& target, const std::string& headers = "") {
  return method + " " + target + " HTTP/1.1\r\nHost: pointdagd\r\n" + headers + "\r\n";
}

// `n` connections from `source`, each answered once (/livez) and then held open.
std::vector<RawSocket> HoldServedConnections(const Daemon& daemon, int n, const char* source = "127.0.0.1") {
  std::vector<RawSocket> held;
  for (int i = 0; i < n; ++i) {
    held.emplace_back(daemon.port(), source);
    held.back().Send(Request("GET", "/livez"));
    EXPECT_EQ(held.back().ReadResponse().bytes.rfind("HTTP/1.1 200", 0), 0u) << "connection " << i;
  }
  return held;
}

size_t CountResponses(const std::string& bytes) {
  size_t n = 0;
  for (size_t at = 0; (at = bytes.find("HTTP/1.1 ", at)) != std::string::npos; ++at) ++n;
  return n;
}

// Polls /livez on fresh connections until it answers (the daemon frees a slot once it sees a
// connection close); the status of the last try.
int LivezSoon(const Daemon& daemon, const char* source = "127.0.0.1") {
  std::string last;
  for (int i = 0; i < 50; ++i) {
    RawSocket s(daemon.port(), source);
    s.Send(Request("GET", "/livez"));
    last = s.ReadResponse(5).bytes;
    if (last.rfind("HTTP/1.1 200", 0) == 0) return 200;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return last.size() >= 12 ? std::stoi(last.substr(9, 3)) : 0;
}

// Regression: `name=%FF` threw inside the JSON dump: the connection dropped with no answer and
// the upload stayed on disk.
TEST(Transport, InvalidUtf8InTheQueryGetsAnAnswerAndLeavesNoUpload) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "");
  ASSERT_TRUE(daemon->started());
  testing::WriteBytes(scratch / "note.txt", {'h', 'e', 'l', 'l', 'o'});
  auto c = daemon->Connect();
  Response r = *c->Upload("/v1/datasets?name=%FF%FE", scratch / "note.txt", kAuth);
  EXPECT_EQ(r.status, 415);
  EXPECT_TRUE(Json(r).contains("error")) << r.body;
  EXPECT_EQ(Uploads(*daemon), 0u);
  r = *c->Upload("/v1/datasets?name=%FF%FE", TinyLas(), kAuth);
  ASSERT_EQ(r.status, 202) << r.body;
  const nlohmann::json job = WaitForJob(*c, r.Header("location"));
  EXPECT_EQ(job["status"], "done") << job.dump();
  EXPECT_EQ(job["params"]["name"], "\xEF\xBF\xBD\xEF\xBF\xBD");  // each invalid byte became U+FFFD
  EXPECT_EQ(Uploads(*daemon), 0u);
}

// Regression: a Transfer-Encoding other than chunked was read as an empty body and the
// connection stayed open, so the body was answered as a second request.
TEST(Transport, SmuggledRequestsAreRefusedAndNeverAnswered) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "");
  ASSERT_TRUE(daemon->started());
  const std::string smuggled = Request("GET", "/v1/datasets/smuggled");
  for (const std::string& framing : {std::string("Transfer-Encoding: gzip\r\n"), std::string("Transfer-Encoding: identity\r\n"),
                                     std::string("Transfer-Encoding: chunked\r\nContent-Length: 5\r\n"),
                                     std::string("Transfer-Encoding: chunked\r\nTransfer-Encoding: chunked\r\n")}) {
    for (const char* method : {"GET", "POST"}) {
      RawSocket s(daemon->port());
      s.Send(Request(method, method == std::string("GET") ? "/livez" : "/v1/datasets", framing) + smuggled);
      const auto read = s.ReadUntil(10, [](const std::string&) { return false; });
      EXPECT_TRUE(read.closed) << framing;
      EXPECT_EQ(read.bytes.rfind("HTTP/1.1 400", 0), 0u) << framing << read.bytes;
      EXPECT_EQ(CountResponses(read.bytes), 1u) << framing << read.bytes;
      EXPECT_EQ(read.bytes.find("smuggled"), std::string::npos) << read.bytes;
    }
  }
  EXPECT_EQ(LivezSoon(*daemon), 200);
}

// Regression: with two Authorization fields the last one won; fields are combined (RFC 9110), and
// a combined Authorization holds several credentials: 400, even when one of them is right.
TEST(Transport, RepeatedHeaderFieldsAreCombined) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "");
  ASSERT_TRUE(daemon->started());
  RawSocket s(daemon->port());
  s.Send(Request("DELETE", "/v1/datasets/0000000000000000",
                 "Authorization: Bearer wrong\r\nAuthorization: Bearer " + std::string(kToken) + "\r\n"));
  EXPECT_EQ(s.ReadResponse().bytes.rfind("HTTP/1.1 400", 0), 0u);
}

TEST(Transport, HeaderSizeAndFieldCountAreLimited) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "max_header_bytes = 2048\nmax_header_fields = 10\n");
  ASSERT_TRUE(daemon->started());
  std::string many;
  for (int i = 0; i < 11; ++i) many += "X-Field-" + std::to_string(i) + ": 1\r\n";
  RawSocket a(daemon->port());
  a.Send(Request("GET", "/livez", many));
  auto read = a.ReadUntil(10, [](const std::string&) { return false; });
  EXPECT_EQ(read.bytes.rfind("HTTP/1.1 431", 0), 0u) << read.bytes;
  EXPECT_NE(read.bytes.find("at most 10 are read"), std::string::npos) << read.bytes;
  EXPECT_TRUE(read.closed);
  RawSocket b(daemon->port());
  b.Send(Request("GET", "/livez", "X-Big: " + std::string(3000, 'x') + "\r\n"));
  read = b.ReadUntil(10, [](const std::string&) { return false; });
  EXPECT_EQ(read.bytes.rfind("HTTP/1.1 431", 0), 0u) << read.bytes;
  EXPECT_TRUE(read.closed);
  RawSocket garbage(daemon->port());
  garbage.Send("\x01\x02 not http\r\n\r\n");
  read = garbage.ReadUntil(10, [](const std::string&) { return false; });
  EXPECT_EQ(read.bytes.rfind("HTTP/1.1 400", 0), 0u) << read.bytes;
  EXPECT_TRUE(read.closed);
}

// Each phase has its own deadline (set to 1 s here; every default was 60 s or 30 min before).
TEST(Transport, EveryConnectionPhaseHasADeadline) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "header_timeout_s = 1\nidle_timeout_s = 1\nbody_timeout_s = 1\nwrite_timeout_s = 1\n");
  ASSERT_TRUE(daemon->started());
  const auto closed_within = [](RawSocket& s, double seconds) { return s.ReadUntil(seconds, [](const std::string&) { return false; }).closed; };
  RawSocket header(daemon->port());
  header.Send("GET /livez HTTP/1.1\r\nHost: x\r\n");  // never finished
  EXPECT_TRUE(closed_within(header, 15));
  RawSocket idle(daemon->port());
  idle.Send(Request("GET", "/livez"));
  EXPECT_EQ(idle.ReadResponse().bytes.rfind("HTTP/1.1 200", 0), 0u);
  EXPECT_TRUE(closed_within(idle, 15));  // kept alive, then idle too long
  RawSocket body(daemon->port());
  body.Send(Request("GET", "/livez", "Content-Length: 10\r\n") + "abc");
  EXPECT_TRUE(closed_within(body, 15));

  // A client that sends requests and never reads the answers: once the socket buffers are full,
  // the write deadline ends the connection instead of holding it (and its session) forever.
  RawSocket deaf(daemon->port());
  const std::string request = Request("GET", "/metrics");
  std::string burst;
  while (burst.size() < (8u << 20)) burst += request;
  std::thread sender([&] { deaf.Send(burst); });  // blocks while the daemon is blocked, fails once it closes
  std::this_thread::sleep_for(std::chrono::seconds(4));
  const auto read = deaf.ReadUntil(30, [](const std::string&) { return false; });
  EXPECT_TRUE(read.closed);
  EXPECT_LT(CountResponses(read.bytes), burst.size() / request.size());
  deaf.Close();
  sender.join();
  EXPECT_EQ(LivezSoon(*daemon), 200);
}

// Regression: there was no cap on connections. Over it a new client gets 503 at once and the
// connection closes; once connections end, the daemon serves again.
TEST(Transport, ConnectionCapRefusesCleanlyAndRecovers) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "max_connections = 8\n");
  ASSERT_TRUE(daemon->started());
  std::vector<RawSocket> held = HoldServedConnections(*daemon, 8);
  ASSERT_FALSE(::testing::Test::HasFailure());
  RawSocket over(daemon->port());
  const auto read = over.ReadUntil(10, [](const std::string&) { return false; });
  EXPECT_EQ(read.bytes.rfind("HTTP/1.1 503", 0), 0u) << read.bytes;
  EXPECT_NE(read.bytes.find("serves 8 connections at once"), std::string::npos) << read.bytes;
  EXPECT_NE(read.bytes.find("Retry-After: 5"), std::string::npos);
  EXPECT_TRUE(read.closed);
  held.clear();
  EXPECT_EQ(LivezSoon(*daemon), 200);
}

// One address cannot take every connection: another client is still served.
TEST(Transport, PerClientCapKeepsRoomForOthers) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "max_connections_per_client = 4\n");
  ASSERT_TRUE(daemon->started());
  std::vector<RawSocket> greedy = HoldServedConnections(*daemon, 4, "127.0.0.2");
  ASSERT_FALSE(::testing::Test::HasFailure());
  RawSocket fifth(daemon->port(), "127.0.0.2");
  const auto read = fifth.ReadUntil(10, [](const std::string&) { return false; });
  EXPECT_EQ(read.bytes.rfind("HTTP/1.1 503", 0), 0u) << read.bytes;
  EXPECT_NE(read.bytes.find("too many connections from your address (at most 4)"), std::string::npos) << read.bytes;
  EXPECT_EQ(LivezSoon(*daemon, "127.0.0.1"), 200);
}

// Utime + stime of a process, in seconds.
double CpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream fields(stat.substr(stat.rfind(')') + 2));
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// Regression: when accept failed for want of file descriptors the loop retried at once (91 % of a
// core while nothing could change). Now it waits 100 ms between tries: a spinning loop would burn
// about a core-second per second here; the bound allows a quarter of that.
TEST(Transport, AcceptBacksOffWhenOutOfFileDescriptors) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "", [](Daemon& d) { d.LimitOpenFiles(48); });
  ASSERT_TRUE(daemon->started());
  std::vector<RawSocket> flood;
  for (int i = 0; i < 80; ++i) flood.emplace_back(daemon->port());  // more than it can accept: the rest wait in the backlog
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const double before = CpuSeconds(daemon->pid());
  std::this_thread::sleep_for(std::chrono::seconds(4));
  EXPECT_LT(CpuSeconds(daemon->pid()) - before, 1.0);
  EXPECT_NE(daemon->Log().find("accept failed: Too many open files; retrying every 100 ms"), std::string::npos) << daemon->Log();
  flood.clear();
  EXPECT_EQ(LivezSoon(*daemon), 200);
}

// Polls until the daemon's uploads/ folder is empty (a session removes its file as it ends).
bool UploadsEmptySoon(const Daemon& daemon) {
  for (int i = 0; i < 100 && Uploads(daemon) > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  return Uploads(daemon) == 0;
}

std::string UploadHead(const std::string& framing) {
  return Request("POST", "/v1/datasets", "Authorization: Bearer " + std::string(kToken) + "\r\n" + framing);
}

// Regression: uploads had no cap. Over it: 503 + Retry-After, before any body is stored.
TEST(TransportUploads, ConcurrentUploadsAreCapped) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "max_uploads = 1\n");
  ASSERT_TRUE(daemon->started());
  RawSocket first(daemon->port());
  first.Send(UploadHead("Content-Length: 1000000\r\n") + std::string(100, 'x'));
  for (int i = 0; i < 100 && Uploads(*daemon) == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_EQ(Uploads(*daemon), 1u);
  auto c = daemon->Connect();
  const Response r = *c->Upload("/v1/datasets", TinyLas(), kAuth);
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(r.Header("retry-after"), "30");
  EXPECT_EQ(Json(r)["error"], "the daemon takes 1 uploads at once; try again later");
  first.Close();  // the client goes away mid-upload: its file goes too, and the slot is free again
  EXPECT_TRUE(UploadsEmptySoon(*daemon));
  c = daemon->Connect();
  EXPECT_EQ(c->Upload("/v1/datasets", TinyLas(), kAuth)->status, 202);
}

// Regression: free disk was never checked; Content-Length + the reserve must fit before a byte is read.
TEST(TransportUploads, AnUploadThatWouldFillTheDiskIsRefusedFirst) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "disk_reserve_mb = 1073741824\n");  // a petabyte must stay free
  ASSERT_TRUE(daemon->started());
  auto c = daemon->Connect();
  const Response r = *c->Upload("/v1/datasets", TinyLas(), kAuth);
  EXPECT_EQ(r.status, 507);
  EXPECT_EQ(Json(r)["error"].get<std::string>().rfind("the daemon's disk is full: ", 0), 0u) << r.body;
  EXPECT_EQ(Uploads(*daemon), 0u);
}

// Regression: running out of space while streaming was answered "400 malformed upload". The
// uploads folder is a 1 MiB tmpfs in the daemon's own mount namespace (unshare), and a chunked
// body (no Content-Length to check first) outgrows it.
TEST(TransportUploads, OutOfSpaceWhileStreamingIs507AndFreesTheSpace) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  const auto uploads = scratch / "var" / "uploads";
  std::filesystem::create_directories(uploads);
  auto daemon = StartDaemon(scratch, "disk_reserve_mb = 0\n", [&](Daemon& d) {
    d.RunUnder({"unshare", "-m", "sh", "-c", "mount -t tmpfs -o size=1m tmpfs \"$0\" && exec \"$@\"", uploads.string()});
  });
  ASSERT_TRUE(daemon->started());
  RawSocket s(daemon->port());
  std::string body = UploadHead("Transfer-Encoding: chunked\r\n");
  const std::string chunk(64 * 1024, 'x');
  for (int i = 0; i < 32; ++i) body += "10000\r\n" + chunk + "\r\n";
  body += "0\r\n\r\n";
  std::thread sender([&] { s.Send(body); });  // fails once the daemon closes
  const auto read = s.ReadResponse(30);
  sender.join();
  EXPECT_EQ(read.bytes.rfind("HTTP/1.1 507", 0), 0u) << read.bytes.substr(0, 300);
  EXPECT_NE(read.bytes.find("\"error\": \"the daemon's disk is full\""), std::string::npos) << read.bytes.substr(0, 300);
  // The partial file was removed: the small tmpfs takes a whole scan again.
  auto c = daemon->Connect();
  const Response r = *c->Upload("/v1/datasets", TinyLas(), kAuth);
  EXPECT_EQ(r.status, 202) << r.body;
}

// Regression: an upload had 30 minutes however slowly it came. Now each window (1 s here) must
// bring upload_min_rate × window bytes; a trickle is cut off and its file removed.
TEST(TransportUploads, AnUploadBelowTheMinimumRateIsCutOff) {
  testing::ScratchDir scratch;
  auto daemon = StartDaemon(scratch, "upload_min_rate = 1000\nupload_rate_window_s = 1\n");
  ASSERT_TRUE(daemon->started());
  RawSocket s(daemon->port());
  s.Send(UploadHead("Content-Length: 100000\r\n"));
  bool closed = false;
  for (int i = 0; i < 100 && !closed; ++i) {  // 50 bytes/s, for at most 20 s
    closed = !s.Send(std::string(10, 'x')) || s.ReadUntil(0.2, [](const std::string&) { return false; }).closed;
  }
  EXPECT_TRUE(closed);
  EXPECT_TRUE(UploadsEmptySoon(*daemon));
  EXPECT_NE(daemon->Log().find("upload cut off: less than 1000 bytes in 1 s"), std::string::npos);
}

}  // namespace
}  // namespace pointdag
