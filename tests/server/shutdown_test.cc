// A clean stop (SIGTERM, as `docker stop` sends it): no job is lost, whether the running one
// finishes within the grace period or resumes from its upload on the next start.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "daemon_util.h"
#include "store_util.h"
#include "test_util.h"

namespace pointdag {
namespace {

using client::Connection;

// A daemon configured with `grace_s`; its store, folder and log under `scratch`.
Daemon WithGrace(const testing::ScratchDir& scratch, int grace_s) {
  std::ofstream(scratch / "pointdagd.toml") << "shutdown_grace_s = " << grace_s << "\n";
  return Daemon(scratch.path(), {"--config", (scratch / "pointdagd.toml").string()});
}

// Uploads lion and waits until its ingest runs.
std::string StartLionIngest(Connection& c) {
  const std::string location = SubmitScan(c, "lion_takanawa_pdrf7_rgb.las", "name=lion");
  for (int i = 0; i < 1000 && !location.empty(); ++i) {
    if (Json(*c.Request("GET", location))["status"] == "running") return location;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ADD_FAILURE() << "the ingest never ran";
  return location;
}

TEST(Shutdown, SigtermLetsTheRunningJobFinishWithinTheGracePeriod) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  Daemon daemon = WithGrace(scratch, 120);
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  StartLionIngest(*c);
  // A second upload waits in the queue: it must not start during the grace period.
  const std::string queued = SubmitScan(*c, "autzen_trim_pdrf3_rgb.las", "name=autzen");
  EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.Log();
  EXPECT_NE(daemon.Log().find("finished 1 running job(s) before leaving"), std::string::npos) << daemon.Log();
  EXPECT_EQ(testing::QueryText(daemon.store(), "SELECT state FROM jobs WHERE params LIKE '%lion%'"), "done");
  EXPECT_EQ(testing::QueryText(daemon.store(), "SELECT state FROM jobs WHERE params LIKE '%autzen%'"), "queued");
  EXPECT_EQ(testing::QueryText(daemon.store(), "SELECT COUNT(*) FROM datasets"), "1");

  // The queued one runs on the next start.
  ASSERT_TRUE(daemon.Start());
  c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(WaitForJob(*c, queued)["status"], "done");
}

TEST(Shutdown, AJobStillRunningAfterTheGracePeriodResumesWithoutLosingAnAttempt) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  Daemon daemon = WithGrace(scratch, 0);
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  const std::string location = StartLionIngest(*c);
  EXPECT_EQ(daemon.Stop(SIGTERM), 0) << daemon.Log();
  EXPECT_NE(daemon.Log().find("leaving with 1 job(s) still running after the 0 s grace period"), std::string::npos) << daemon.Log();
  EXPECT_EQ(testing::QueryText(daemon.store(), "SELECT COUNT(*) FROM datasets"), "0");
  EXPECT_EQ(testing::QueryText(daemon.store(), "SELECT attempts FROM jobs"), "0");  // a clean stop is not a crash

  ASSERT_TRUE(daemon.Start());
  c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  const nlohmann::json job = WaitForJob(*c, location);
  EXPECT_EQ(job["status"], "done") << job.dump();
  EXPECT_EQ(testing::QueryText(daemon.store(), "SELECT attempts FROM jobs"), "1");
  EXPECT_EQ(testing::QueryText(daemon.store(), "SELECT COUNT(*) FROM datasets"), "1");
}

}  // namespace
}  // namespace pointdag
