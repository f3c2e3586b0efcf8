// pointdagd's start: the config's checks, where tokens come from (and that they never reach the
// log), the rule that an open daemon stays on loopback, the sweep of a crash's leftovers.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <fstream>

#include "daemon_util.h"
#include "test_util.h"

namespace pointdag {
namespace {

struct Exit {
  int code = -1;
  std::string log;
};

// Runs pointdagd with `args` (at most 20 s; 124 when it was still serving) and returns its exit code and output.
Exit RunToExit(const testing::ScratchDir& scratch, const std::string& args) {
  const auto log = scratch / "run.log";
  const std::string command = std::string("timeout 20 ") + POINTDAGD + " --data-dir " + (scratch / "var").string() + " " + args + " >" +
                              log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  const auto bytes = testing::ReadBytes(log);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, std::string(bytes.begin(), bytes.end())};
}

// Regression: with no token the daemon listened on any address it was given.
TEST(DaemonStart, RefusesToListenBeyondLoopbackWithoutAToken) {
  testing::ScratchDir scratch;
  const Exit exit = RunToExit(scratch, "--listen 0.0.0.0:0");
  EXPECT_EQ(exit.code, 2) << exit.log;
  EXPECT_NE(exit.log.find("refusing to listen on 0.0.0.0 without a token"), std::string::npos) << exit.log;
  EXPECT_NE(exit.log.find("--no-token"), std::string::npos);
}

TEST(DaemonStart, NoTokenFlagOpensItOnPurpose) {
  testing::ScratchDir scratch;
  Daemon daemon(scratch.path(), {"--no-token"});
  daemon.WithoutTokenFlag();
  daemon.ListenOn("0.0.0.0");
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  EXPECT_EQ(c->Request("GET", "/livez")->status, 200);
  EXPECT_NE(daemon.Log().find("pointdagd listening on http://0.0.0.0:"), std::string::npos) << daemon.Log();
}

// The write token from the environment or a file works like --token, and no log line (trace
// level included) ever holds it.
TEST(DaemonStart, TokensFromTheEnvironmentOrAFileAreNeverLogged) {
  testing::ScratchDir scratch;
  std::ofstream(scratch / "pointdagd.toml") << "log_level = \"trace\"\n";
  std::ofstream(scratch / "token") << "file-secret-5678\n";
  const std::string config = (scratch / "pointdagd.toml").string();
  for (const bool from_file : {false, true}) {
    Daemon daemon(scratch.path(), from_file ? std::vector<std::string>{"--config", config, "--token-file", (scratch / "token").string()}
                                            : std::vector<std::string>{"--config", config});
    daemon.WithoutTokenFlag();
    daemon.SetEnv("POINTDAGD_TOKEN", "env-secret-1234");
    daemon.SetEnv("POINTDAGD_READ_TOKEN", "env-read-secret-9012");
    ASSERT_TRUE(daemon.Start());
    const std::string token = from_file ? "file-secret-5678" : "env-secret-1234";
    auto c = daemon.Connect();
    EXPECT_EQ(c->Request("DELETE", "/v1/datasets/0000000000000000")->status, 401);
    EXPECT_EQ(c->Request("DELETE", "/v1/datasets/0000000000000000", {{"Authorization", "Bearer " + token}})->status, 404);
    daemon.Stop(SIGTERM);
    const std::string log = daemon.Log();
    EXPECT_NE(log.find("token required for writes, read token set"), std::string::npos) << log;
    for (const char* secret : {"secret-5678", "secret-1234", "secret-9012"}) EXPECT_EQ(log.find(secret), std::string::npos) << log;
  }
  std::ofstream(scratch / "empty-token") << "\n";
  const Exit exit = RunToExit(scratch, "--listen 127.0.0.1:0 --token-file " + (scratch / "empty-token").string());
  EXPECT_EQ(exit.code, 2);
  EXPECT_NE(exit.log.find("has no token on its first line"), std::string::npos) << exit.log;
}

// Regression: uploads and spill files a crash left behind stayed forever.
TEST(DaemonStart, SweepsWhatACrashLeftBehind) {
  testing::ScratchDir scratch;
  std::filesystem::create_directories(scratch / "var" / "uploads");
  std::filesystem::create_directories(scratch / "var" / "spill" / "job");
  std::ofstream(scratch / "var" / "uploads" / "0123456789abcdef.upload") << "half a scan";
  std::ofstream(scratch / "var" / "spill" / "job" / "chunk.bin") << "spilled points";
  Daemon daemon(scratch.path());
  ASSERT_TRUE(daemon.Start());
  EXPECT_TRUE(std::filesystem::is_empty(scratch / "var" / "uploads"));
  EXPECT_TRUE(std::filesystem::is_empty(scratch / "var" / "spill"));
  EXPECT_NE(daemon.Log().find("swept 2 file(s) a previous run left in uploads/ and spill/"), std::string::npos) << daemon.Log();
}

// A mistyped or out-of-range setting stops the start with the key's name, never passes silently.
TEST(DaemonStart, ConfigMistakesStopTheStart) {
  testing::ScratchDir scratch;
  const std::pair<const char*, const char*> cases[] = {
      {"workers = \"two\"\n", "workers must be an integer"},
      {"max_connections = 0\n", "max_connections must be between 1 and 1048576"},
      {"max_upload_bytes = -1\n", "max_upload_bytes must be between 1 and"},
      {"cors_origins = \"*\"\n", "cors_origins must be a non-empty array of strings"},
      {"header_timeout = 5\n", "unknown key 'header_timeout'"},
      {"log_level = \"loud\"\n", "log_level must be trace, debug"},
      {"listen = \n", "pointdagd.toml"},
      {"nightly = 1\n", "nightly must be a table"},
      {"[nightly]\ntime = \"03:15\"\n", "[nightly]: corpus is required"},
      {"[nightly]\ncorpus = \"c.toml\"\ntime = \"25:00\"\n", "time must be \"HH:MM\" (UTC), got '25:00'"},
      {"[nightly]\ncorpus = \"c.toml\"\nkept = 3\n", "[nightly]: unknown key 'kept'"},
  };
  for (const auto& [toml, message] : cases) {
    std::ofstream(scratch / "pointdagd.toml") << toml;
    const Exit exit = RunToExit(scratch, "--config " + (scratch / "pointdagd.toml").string());
    EXPECT_EQ(exit.code, 2) << toml;
    EXPECT_NE(exit.log.find(message), std::string::npos) << toml << exit.log;
  }
}

// The shipped configuration is valid as it stands.
TEST(DaemonStart, TheShippedConfigLoads) {
  // The container's and the production example's too (the test's flags put them on loopback and a
  // scratch folder).
  for (const char* config : {"pointdagd.toml", "container.toml", "production.toml"}) {
    testing::ScratchDir scratch;
    Daemon daemon(scratch.path(), {"--config", std::string(POINTDAG_SOURCE_DIR) + "/configs/" + config});
    ASSERT_TRUE(daemon.Start()) << config;
    auto c = daemon.Connect();
    EXPECT_EQ(c->Request("GET", "/livez")->status, 200) << config;
  }
}

}  // namespace
}  // namespace pointdag
