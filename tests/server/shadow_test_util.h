// Helpers of the shadow server tests (shadow_server_test.cc, shadow_query_test.cc): requests with
// the write token, error messages, a shadows job run, pointdagd --check (a scan is ingested by
// daemon_util.h's IngestScan).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <utility>

#include "daemon_util.h"
#include "test_util.h"

namespace pointdag {

inline std::span<const uint8_t> Bytes(const std::string& s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

inline client::Response Post(client::Connection& c, const std::string& target, const std::string& body, bool auth = true) {
  auto headers = auth ? kAuth : std::map<std::string, std::string>{};
  headers["Content-Type"] = "application/json";
  return *c.Request("POST", target, headers, body);
}

inline std::string ErrorOf(const client::Response& r) {
  const nlohmann::json j = Json(r);
  return j.is_object() && j.contains("error") && j["error"].is_string() ? j["error"].get<std::string>() : "(no error member) " + r.body;
}

// A suite with its own pointdagd named Suite::kDaemonName, started by its first test (SuiteDaemon),
// skipped with the reason when ../shared/data is absent.
template <typename Suite>
class ShadowSuite : public ::testing::Test {
 protected:
  void SetUp() override {
    SKIP_WITHOUT_DATA();
    ASSERT_TRUE(daemon_.Start()) << "the suite's pointdagd did not start";
  }
  static void TearDownTestSuite() { daemon_.Stop(); }
  static std::string Ingest(const std::string& scan, const std::string& query) {
    return IngestScan(*daemon_->Connect(), scan, query);
  }
  static inline SuiteDaemon daemon_{Suite::kDaemonName};
};

// Posts a shadows request and waits for its job; the job's last state.
inline nlohmann::json Shade(client::Connection& c, const std::string& dataset, const std::string& body) {
  const client::Response r = Post(c, dataset + "/shadows", body);
  EXPECT_EQ(r.status, 202) << r.body;
  if (r.status != 202) return {};
  EXPECT_EQ(Json(r)["kind"], "shadows");
  return WaitForJob(c, r.Header("location"));
}

// Ingests `scan` into `daemon` and has a shadow set computed for `body`: the dataset's id, or "" with a
// test failure.
inline std::string IngestAndShade(Daemon& daemon, const std::string& scan, const std::string& query,
                                  const std::string& body) {
  auto c = daemon.Connect();
  const std::string dataset = IngestScan(*c, scan, query);
  if (dataset.empty()) return "";
  const nlohmann::json job = Shade(*c, dataset, body);
  EXPECT_EQ(job["status"], "done") << job.dump();
  return job["status"] == "done" ? dataset.substr(std::string("/v1/datasets/").size()) : "";
}

// pointdagd --check on a stopped daemon's folder: exit code and output.
inline std::pair<int, std::string> RunCheck(const std::filesystem::path& var) {
  std::string out;
  FILE* pipe = popen((std::string(POINTDAGD) + " --data-dir " + var.string() + " --check 2>&1").c_str(), "r");
  char buffer[4096];
  for (size_t n; pipe && (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;) out.append(buffer, n);
  const int status = pipe ? pclose(pipe) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace pointdag
