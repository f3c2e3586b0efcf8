#include "daemon_util.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "test_util.h"

namespace pointdag {

const std::map<std::string, std::string> kAuth = {{"Authorization", std::string("Bearer ") + kToken}};

void Daemon::Start() {
  const auto port_file = data_dir_ / "port";
  std::filesystem::create_directories(data_dir_);
  std::filesystem::remove(port_file);
  pid_ = fork();
  if (pid_ == 0) {
    std::vector<std::string> args = {POINTDAGD, "--listen", "127.0.0.1:0", "--data-dir", (data_dir_ / "var").string(),
                                     "--port-file", port_file.string(), "--token", kToken};
    args.insert(args.end(), extra_.begin(), extra_.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int log = ::open((data_dir_ / "daemon.log").c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(log, 1);
    dup2(log, 2);
    execv(argv[0], argv.data());
    _exit(127);
  }
  for (int i = 0; i < 200 && !std::filesystem::exists(port_file); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(25));
  ASSERT_TRUE(std::filesystem::exists(port_file)) << "pointdagd did not start; see " << data_dir_ / "daemon.log";
  const auto bytes = testing::ReadBytes(port_file);
  port_ = static_cast<uint16_t>(std::stoi(std::string(bytes.begin(), bytes.end())));
}

void Daemon::Stop(int signal) {
  if (pid_ <= 0) return;
  kill(pid_, signal);
  int status = 0;
  waitpid(pid_, &status, 0);
  pid_ = -1;
}

std::unique_ptr<client::Connection> Daemon::Connect() const {
  auto c = client::Connection::Open("127.0.0.1", port_);
  EXPECT_TRUE(c.ok()) << c.status().ToString();
  return c.ok() ? std::move(*c) : nullptr;
}

nlohmann::json Json(const client::Response& r) { return nlohmann::json::parse(r.body, nullptr, false); }

nlohmann::json WaitForJob(client::Connection& c, const std::string& location) {
  nlohmann::json job;
  for (int i = 0; i < 1200; ++i) {
    job = Json(*c.Request("GET", location));
    if (job["status"] == "done" || job["status"] == "failed") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return job;
}

}  // namespace pointdag
