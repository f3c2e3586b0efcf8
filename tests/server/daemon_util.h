// A real pointdagd started by a test on loopback, and the small helpers the server tests share.
#pragma once

#include <signal.h>
#include <sys/types.h>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "client.h"

namespace pointdag {

inline constexpr const char* kToken = "s3cret";
extern const std::map<std::string, std::string> kAuth;

// One daemon process: started with a fresh or kept data folder, stopped by a signal of our choice.
class Daemon {
 public:
  explicit Daemon(std::filesystem::path data_dir, std::vector<std::string> extra = {})
      : data_dir_(std::move(data_dir)), extra_(std::move(extra)) {}
  ~Daemon() { Stop(SIGKILL); }

  // Before Start(): no --token flag; another address than 127.0.0.1 (any port); a limit on open files; a command the daemon runs under (its
  // argv is appended: e.g. unshare for a private mount); an environment variable.
  void WithoutTokenFlag() { token_flag_ = false; }
  void ListenOn(std::string host) { host_ = std::move(host); }
  void LimitOpenFiles(int limit) { open_files_ = limit; }
  void RunUnder(std::vector<std::string> wrapper) { wrapper_ = std::move(wrapper); }
  void SetEnv(std::string name, std::string value) { env_.emplace_back(std::move(name), std::move(value)); }

  // Starts the daemon and waits for its port; on failure records a (non-fatal) test failure with
  // the daemon's log, leaves started() false and returns false.
  bool Start();
  bool started() const { return port_ != 0; }
  // Sends `signal` and waits: the exit code, 128 + the signal that ended it, or -1 when none ran.
  int Stop(int signal);
  pid_t pid() const { return pid_; }
  std::string Log() const;
  std::filesystem::path var() const { return data_dir_ / "var"; }
  std::unique_ptr<client::Connection> Connect() const;
  uint16_t port() const { return port_; }
  std::filesystem::path store() const { return data_dir_ / "var" / "store.sqlite"; }

 private:
  std::filesystem::path data_dir_;
  std::vector<std::string> extra_;
  bool token_flag_ = true;
  std::string host_ = "127.0.0.1";
  std::optional<int> open_files_;
  std::vector<std::string> wrapper_;
  std::vector<std::pair<std::string, std::string>> env_;
  pid_t pid_ = -1;
  uint16_t port_ = 0;
};

// One daemon shared by a test suite, started by the suite's first test: from SetUp(), not
// SetUpTestSuite(), because gtest skips every test of a suite whose SetUpTestSuite() records a
// failure and ctest counts those as "Skipped"; here a daemon that does not start fails each test,
// with its log.
class SuiteDaemon {
 public:
  explicit SuiteDaemon(std::string name) : name_(std::move(name)) {}
  // Starts it in a fresh temporary folder on the first call; whether it runs.
  bool Start();
  // Stops it and removes its folder (for TearDownTestSuite()).
  void Stop();
  Daemon* operator->() const { return daemon_.get(); }
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::string name_;
  std::filesystem::path dir_;
  std::unique_ptr<Daemon> daemon_;
};

// A plain TCP client for what the HTTP client will not send: raw bytes, a chosen source address
// on 127/8 (the daemon's per-client cap), partial requests, and reads with a deadline.
class RawSocket {
 public:
  explicit RawSocket(uint16_t port, const char* source = "127.0.0.1");
  ~RawSocket();
  RawSocket(RawSocket&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  RawSocket& operator=(RawSocket&&) = delete;
  bool connected() const { return fd_ >= 0; }
  bool Send(std::string_view bytes);
  // Reads until `done(received)` holds, the peer closes, or `seconds` pass.
  struct Read {
    std::string bytes;
    bool closed = false;  // the peer closed (or reset) the connection
  };
  Read ReadUntil(double seconds, const std::function<bool(const std::string&)>& done = {});
  // One whole response (header and Content-Length body), or what came before the deadline.
  Read ReadResponse(double seconds = 10);
  void Close();

 private:
  int fd_ = -1;
};

nlohmann::json Json(const client::Response& r);
// Polls a job until it ends; returns its last state.
nlohmann::json WaitForJob(client::Connection& c, const std::string& location);
// Uploads `scan` (a file of ../shared/data) with the write token; returns the job's Location, or ""
// with a test failure when the daemon does not take it with 202.
std::string SubmitScan(client::Connection& c, const std::string& scan, const std::string& query);
// SubmitScan, then waits for the job: the dataset's path (/v1/datasets/ID), or "" with a test failure.
std::string IngestScan(client::Connection& c, const std::string& scan, const std::string& query);

}  // namespace pointdag
