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

// Posts a shadows request and waits for its job; the job's last state.
inline nlohmann::json Shade(client::Connection& c, const std::string& dataset, const std::string& body) {
  const client::Response r = Post(c, dataset + "/shadows", body);
  EXPECT_EQ(r.status, 202) << r.body;
  if (r.status != 202) return {};
  EXPECT_EQ(Json(r)["kind"], "shadows");
  return WaitForJob(c, r.Header("location"));
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
