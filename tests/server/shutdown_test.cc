// A clean stop (SIGTERM, as `docker stop` sends it): no job is lost, whether the running one
// finishes within the grace period or resumes from its upload on the next start.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <memory>
#include <thread>

#include "daemon_util.h"
#include "store_util.h"
#include "test_util.h"

namespace pointdag {
namespace {

using client::Connection;

// A daemon configured with `grace_s` (its store, folder and log in a scratch folder), with lion's
// ingest running on it.
class Shutdown : public ::testing::Test {
 protected:
  void StartLionIngest(int grace_s) {
    std::ofstream(scratch_ / "pointdagd.toml") << "shutdown_grace_s = " << grace_s << "\n";
    daemon_ = std::make_unique<Daemon>(scratch_.path(), std::vector<std::string>{"--config", (scratch_ / "pointdagd.toml").string()});
    ASSERT_TRUE(daemon_->Start());
    c_ = daemon_->Connect();
    ASSERT_NE(c_, nullptr);
    lion_ = SubmitScan(*c_, "lion_takanawa_pdrf7_rgb.las", "name=lion");
    for (int i = 0; i < 1000 && !lion_.empty(); ++i) {
      if (Json(*c_->Request("GET", lion_))["status"] == "running") return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    FAIL() << "the ingest never ran";
  }

  testing::ScratchDir scratch_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Connection> c_;
  std::string lion_;  // the job's location
};

TEST_F(Shutdown, SigtermLetsTheRunningJobFinishWithinTheGracePeriod) {
  SKIP_WITHOUT_DATA();
  ASSERT_NO_FATAL_FAILURE(StartLionIngest(120));
  Daemon& daemon = *daemon_;
  auto& c = c_;
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

TEST_F(Shutdown, AJobStillRunningAfterTheGracePeriodResumesWithoutLosingAnAttempt) {
  SKIP_WITHOUT_DATA();
  ASSERT_NO_FATAL_FAILURE(StartLionIngest(0));
  Daemon& daemon = *daemon_;
  auto& c = c_;
  const std::string location = lion_;
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
