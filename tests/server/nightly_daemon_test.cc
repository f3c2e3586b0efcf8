// pointdagd's [nightly] schedule: the benchmark fires, its reports are served, /metrics shows them.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "daemon_util.h"
#include "test_util.h"

namespace pointdag {
namespace {

TEST(Nightly, TheScheduleFiresAndTheReportIsServed) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  std::ofstream(scratch / "corpus.toml") << "targets = [38.0]\n[[scan]]\nfile = \""
                                         << (testing::DataDir() / "tiny_1.2-with-color_1065pts.las").string() << "\"\nvoxel = 8.0\n";
  std::ofstream(scratch / "pointdagd.toml") << "[nightly]\ncorpus = \"" << (scratch / "corpus.toml").string()
                                            << "\"\ninterval_s = 1\nreports_kept = 2\ncommand = \"" << POINTDAG_CLI << "\"\n";
  Daemon daemon(scratch.path(), {"--config", (scratch / "pointdagd.toml").string()});
  daemon.SetEnv("POINTDAG_DEVICE", "cpu");
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  ASSERT_TRUE(c);

  nlohmann::json reports;
  for (int i = 0; i < 600; ++i) {
    auto list = c->Request("GET", "/v1/reports");
    ASSERT_TRUE(list.ok());
    ASSERT_EQ(list->status, 200) << list->body;
    reports = Json(*list)["reports"];
    if (!reports.empty()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_FALSE(reports.empty()) << daemon.Log();
  const std::string id = reports[0]["id"];
  EXPECT_EQ(reports[0]["cases"], 1);
  EXPECT_EQ(reports[0]["failed_cases"], 0);

  auto json = c->Request("GET", "/v1/reports/" + id);
  ASSERT_TRUE(json.ok());
  EXPECT_EQ(json->status, 200);
  EXPECT_EQ(json->Header("content-type"), "application/json");
  const auto report = Json(*json);
  EXPECT_EQ(report["id"], id);
  EXPECT_EQ(report["cases"][0]["voxels"], 1063);

  auto html = c->Request("GET", "/v1/reports/" + id + ".html");
  ASSERT_TRUE(html.ok());
  EXPECT_EQ(html->status, 200);
  EXPECT_EQ(html->Header("content-type"), "text/html; charset=utf-8");
  EXPECT_NE(html->body.find("<svg"), std::string::npos);

  auto latest = c->Request("GET", "/reports/latest.html");
  ASSERT_TRUE(latest.ok());
  EXPECT_EQ(latest->status, 200);
  EXPECT_NE(latest->body.find("pointdag compression benchmark"), std::string::npos);

  auto bad = c->Request("GET", "/v1/reports/..%2Fstore.sqlite");
  ASSERT_TRUE(bad.ok());
  EXPECT_EQ(bad->status, 400);
  auto missing = c->Request("GET", "/v1/reports/19990101T000000Z");
  ASSERT_TRUE(missing.ok());
  EXPECT_EQ(missing->status, 404);
  EXPECT_NE(missing->body.find("no report 19990101T000000Z"), std::string::npos) << missing->body;
  auto post = c->Request("POST", "/v1/reports", kAuth);
  ASSERT_TRUE(post.ok());
  EXPECT_EQ(post->status, 405);

  // /metrics: the run and the report's sizes (the same report or a newer one: runs go on every second).
  bool seen = false;
  for (int i = 0; i < 100 && !seen; ++i) {
    auto metrics = c->Request("GET", "/metrics");
    ASSERT_TRUE(metrics.ok());
    seen = metrics->body.find("pointdag_nightly_last_exit_code 0") != std::string::npos &&
           metrics->body.find("scan=\"tiny_1.2-with-color_1065pts.las\",voxel=\"8\",codec=\"vbr@38\"") != std::string::npos &&
           metrics->body.find("codec=\"draco\"") != std::string::npos;
    if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_TRUE(seen) << daemon.Log();

  // SIGTERM while runs go on: the daemon stops its benchmark child and exits 0, leaving only whole
  // reports (reports_kept = 2).
  daemon.Stop(SIGTERM);
  size_t json_reports = 0;
  for (const auto& entry : std::filesystem::directory_iterator(daemon.var() / "reports")) {
    const std::string name = entry.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    json_reports += entry.path().extension() == ".json" ? 1 : 0;
  }
  EXPECT_GE(json_reports, 1u);
  EXPECT_LE(json_reports, 2u);
}

}  // namespace
}  // namespace pointdag
