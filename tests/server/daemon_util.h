// A real pointdagd started by a test on loopback, and the small helpers the server tests share.
#pragma once

#include <signal.h>
#include <sys/types.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
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

  void Start();
  void Stop(int signal);
  std::unique_ptr<client::Connection> Connect() const;
  uint16_t port() const { return port_; }
  std::filesystem::path store() const { return data_dir_ / "var" / "store.sqlite"; }

 private:
  std::filesystem::path data_dir_;
  std::vector<std::string> extra_;
  pid_t pid_ = -1;
  uint16_t port_ = 0;
};

nlohmann::json Json(const client::Response& r);
// Polls a job until it ends; returns its last state.
nlohmann::json WaitForJob(client::Connection& c, const std::string& location);

}  // namespace pointdag
