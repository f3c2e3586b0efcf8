#include "daemon_util.h"

#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <arpa/inet.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "test_util.h"

namespace pointdag {

const std::map<std::string, std::string> kAuth = {{"Authorization", std::string("Bearer ") + kToken}};

bool Daemon::Start() {
  const auto port_file = data_dir_ / "port";
  std::filesystem::create_directories(data_dir_);
  std::filesystem::remove(port_file);
  pid_ = fork();
  if (pid_ == 0) {
    std::vector<std::string> args = wrapper_;
    args.insert(args.end(), {POINTDAGD, "--listen", host_ + ":0", "--data-dir", (data_dir_ / "var").string(), "--port-file", port_file.string()});
    if (token_flag_) args.insert(args.end(), {"--token", kToken});
    args.insert(args.end(), extra_.begin(), extra_.end());
    for (const auto& [name, value] : env_) setenv(name.c_str(), value.c_str(), 1);
    if (open_files_) {
      const rlimit limit{static_cast<rlim_t>(*open_files_), static_cast<rlim_t>(*open_files_)};
      setrlimit(RLIMIT_NOFILE, &limit);
    }
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int log = ::open((data_dir_ / "daemon.log").c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(log, 1);
    dup2(log, 2);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  // A loaded machine (a parallel ctest, a sanitizer build, a Vulkan calibration) can take many
  // seconds to start a daemon: wait long, but stop at once when the process has already ended.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!std::filesystem::exists(port_file)) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      // A recorded failure and false, not ASSERT (which would only leave this helper): callers
      // ASSERT on the result, so the test itself fails.
      ADD_FAILURE() << "pointdagd exited during start (status " << status << "):\n" << Log();
      return false;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ADD_FAILURE() << "pointdagd did not start within 120 s:\n" << Log();
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  const auto bytes = testing::ReadBytes(port_file);
  port_ = static_cast<uint16_t>(std::stoi(std::string(bytes.begin(), bytes.end())));
  return true;
}

int Daemon::Stop(int signal) {
  if (pid_ <= 0) return -1;
  kill(pid_, signal);
  int status = 0;
  waitpid(pid_, &status, 0);
  pid_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::unique_ptr<client::Connection> Daemon::Connect() const {
  auto c = client::Connection::Open("127.0.0.1", port_);
  EXPECT_TRUE(c.ok()) << c.status().ToString();
  return c.ok() ? std::move(*c) : nullptr;
}

std::string Daemon::Log() const {
  const auto bytes = testing::ReadBytes(data_dir_ / "daemon.log");
  return std::string(bytes.begin(), bytes.end());
}

RawSocket::RawSocket(uint16_t port, const char* source) {
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in from{}, to{};
  from.sin_family = to.sin_family = AF_INET;
  inet_pton(AF_INET, source, &from.sin_addr);
  inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
  to.sin_port = htons(port);
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&from), sizeof from) != 0 ||
      ::connect(fd_, reinterpret_cast<const sockaddr*>(&to), sizeof to) != 0) {
    Close();
  }
}

RawSocket::~RawSocket() { Close(); }

void RawSocket::Close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool RawSocket::Send(std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n <= 0) return false;
    bytes.remove_prefix(static_cast<size_t>(n));
  }
  return true;
}

RawSocket::Read RawSocket::ReadUntil(double seconds, const std::function<bool(const std::string&)>& done) {
  Read read;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!done || !done(read.bytes)) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
    pollfd p{fd_, POLLIN, 0};
    if (left <= 0 || ::poll(&p, 1, static_cast<int>(left)) <= 0) break;
    char chunk[65536];
    const ssize_t n = ::recv(fd_, chunk, sizeof chunk, 0);
    if (n <= 0) {
      read.closed = true;
      break;
    }
    read.bytes.append(chunk, static_cast<size_t>(n));
  }
  return read;
}

RawSocket::Read RawSocket::ReadResponse(double seconds) {
  return ReadUntil(seconds, [](const std::string& bytes) {
    const size_t end = bytes.find("\r\n\r\n");
    if (end == std::string::npos) return false;
    const std::string head = bytes.substr(0, end);
    size_t length = 0;
    for (const char* name : {"Content-Length: ", "content-length: "}) {
      if (const size_t at = head.find(name); at != std::string::npos) length = std::stoul(head.substr(at + std::strlen(name)));
    }
    return bytes.size() >= end + 4 + length;
  });
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

std::string SubmitScan(client::Connection& c, const std::string& scan, const std::string& query) {
  const auto posted = c.Upload("/v1/datasets?" + query, testing::DataDir() / scan, kAuth);
  EXPECT_TRUE(posted.ok() && posted->status == 202) << (posted.ok() ? posted->body : posted.status().ToString());
  return posted.ok() && posted->status == 202 ? posted->Header("location") : "";
}

std::string IngestScan(client::Connection& c, const std::string& scan, const std::string& query) {
  const std::string location = SubmitScan(c, scan, query);
  if (location.empty()) return "";
  const nlohmann::json job = WaitForJob(c, location);
  EXPECT_EQ(job["status"], "done") << job.dump();
  return job["status"] == "done" ? "/v1/datasets/" + job["dataset_id"].get<std::string>() : "";
}


bool SuiteDaemon::Start() {
  if (!daemon_) {
    dir_ = std::filesystem::temp_directory_path() / (name_ + "-" + std::to_string(getpid()));
    std::filesystem::remove_all(dir_);
    daemon_ = std::make_unique<Daemon>(dir_);
    (void)daemon_->Start();
  }
  return daemon_->started();
}

void SuiteDaemon::Stop() {
  daemon_.reset();
  if (!dir_.empty()) std::filesystem::remove_all(dir_);
}

}  // namespace pointdag
