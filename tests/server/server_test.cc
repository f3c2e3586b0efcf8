// A real pointdagd on loopback, started by the test; requests through the proto/ client.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "client.h"
#include "daemon_util.h"
#include "pointdag/color/color_metrics.h"
#include "pointdag/pipeline.h"
#include "store_util.h"
#include "test_util.h"

namespace pointdag {
namespace {

using client::Connection;
using client::Response;

class ServerTest : public ::testing::Test {
 protected:
  // One daemon for the suite, started by its first test (SuiteDaemon says why).
  void SetUp() override { ASSERT_TRUE(daemon_.Start()) << "the suite's pointdagd did not start"; }
  static void TearDownTestSuite() { daemon_.Stop(); }
  // Uploads a scan and waits for its dataset; returns the dataset's metadata.
  static nlohmann::json Ingest(const std::filesystem::path& scan, const std::string& query) {
    auto c = daemon_->Connect();
    auto posted = c->Upload("/v1/datasets?" + query, scan, kAuth);
    EXPECT_TRUE(posted.ok());
    EXPECT_EQ(posted->status, 202) << posted->body;
    const std::string location = posted->Header("location");
    EXPECT_EQ(location.rfind("/v1/jobs/", 0), 0u);
    const nlohmann::json job = WaitForJob(*c, location);
    EXPECT_EQ(job["status"], "done") << job.dump();
    if (job["status"] != "done") return {};
    EXPECT_EQ(job["percent"], 100.0);
    return Json(*c->Request("GET", "/v1/datasets/" + job["dataset_id"].get<std::string>()));
  }
  static inline SuiteDaemon daemon_{"pointdagd-test"};
};

TEST_F(ServerTest, HealthAndMetrics) {
  auto c = daemon_->Connect();
  EXPECT_EQ(c->Request("GET", "/livez")->status, 200);
  EXPECT_EQ(c->Request("GET", "/readyz")->status, 200);
  (void)c->Request("GET", "/v1/datasets/none");
  const Response metrics = *c->Request("GET", "/metrics");
  EXPECT_EQ(metrics.status, 200);
  EXPECT_EQ(metrics.Header("content-type"), "text/plain; version=0.0.4");
  EXPECT_NE(metrics.body.find("pointdag_http_requests_total{route=\"/v1/datasets/{id}\",status=\"404\"} "), std::string::npos);
  EXPECT_NE(metrics.body.find("pointdag_http_request_duration_seconds_bucket{route=\"/livez\",le=\"+Inf\"} 1"), std::string::npos);
  EXPECT_NE(metrics.body.find("pointdag_jobs{state=\"failed\"}"), std::string::npos);
  EXPECT_NE(metrics.body.find("pointdag_ingest_points_per_second"), std::string::npos);
  // Where the stages with Vulkan kernels run, decided at start and said in the log too.
  EXPECT_NE(metrics.body.find("pointdag_stage_device{stage=\"voxelize\",device=\""), std::string::npos) << metrics.body;
  EXPECT_NE(metrics.body.find("pointdag_stage_device{stage=\"color_blocks\",device=\""), std::string::npos) << metrics.body;
  const auto log = testing::ReadBytes(daemon_.dir() / "daemon.log");
  EXPECT_NE(std::string(log.begin(), log.end()).find("stages: voxelize: "), std::string::npos);
  EXPECT_NE(std::string(log.begin(), log.end()).find("; color_blocks: "), std::string::npos);
}

TEST_F(ServerTest, ErrorPathsAnswerWithTheirStatusAndAJsonMessage) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  auto c = daemon_->Connect();
  const auto tiny = testing::DataDir() / "tiny_1.2-with-color_1065pts.las";
  const auto error_of = [](const Response& r) { return Json(r)["error"].get<std::string>(); };

  Response r = *c->Upload("/v1/datasets", tiny);  // no token
  EXPECT_EQ(r.status, 401);
  EXPECT_EQ(r.Header("www-authenticate"), "Bearer");
  c = daemon_->Connect();  // the daemon closes a connection whose body it did not read
  r = *c->Upload("/v1/datasets", tiny, {{"Authorization", "Bearer wrong"}});
  EXPECT_EQ(r.status, 401);

  c = daemon_->Connect();
  r = *c->Request("POST", "/v1/datasets", {{"Authorization", std::string("Bearer ") + kToken}, {"Content-Length", "99999999999999"}});
  EXPECT_EQ(r.status, 413);
  EXPECT_NE(error_of(r).find("at most"), std::string::npos);

  c = daemon_->Connect();
  r = *c->Upload("/v1/datasets?voxel=-1", tiny, kAuth);
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(error_of(r), "voxel must be a positive number");

  // A LAS header whose point format claims LAZ without LASzip's VLR.
  auto laz = testing::ReadBytes(tiny);
  laz[104] |= 0x80;
  testing::WriteBytes(scratch / "x.laz", laz);
  c = daemon_->Connect();
  r = *c->Upload("/v1/datasets", scratch / "x.laz", kAuth);
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(error_of(r), "Malformed: the point format says LAZ but the file has no LASzip VLR");
  testing::WriteBytes(scratch / "note.txt", {'h', 'e', 'l', 'l', 'o'});
  r = *c->Upload("/v1/datasets", scratch / "note.txt", kAuth);
  EXPECT_EQ(r.status, 415);
  EXPECT_EQ(error_of(r), "Unsupported: the upload is not a LAS, LAZ, PLY or PCD scan (unrecognised first bytes)");

  // Truncated LAS: the reader's message, and no job made.
  auto truncated = testing::ReadBytes(tiny);
  truncated.resize(truncated.size() - 1000);
  testing::WriteBytes(scratch / "cut.las", truncated);
  r = *c->Upload("/v1/datasets", scratch / "cut.las", kAuth);
  EXPECT_EQ(r.status, 400);
  EXPECT_NE(error_of(r).find("Truncated: LAS header declares 1065 points"), std::string::npos) << r.body;
  EXPECT_EQ(r.Header("location"), "");

  EXPECT_EQ(c->Request("GET", "/v1/jobs/0000000000000000")->status, 404);
  EXPECT_EQ(c->Request("GET", "/v1/datasets/0000000000000000")->status, 404);
  EXPECT_EQ(c->Request("GET", "/v1/datasets/0000000000000000/tiles/0/0/0/0")->status, 404);
  EXPECT_EQ(c->Request("GET", "/v1/datasets/x/tiles/0/0/zero/0")->status, 400);
  EXPECT_EQ(c->Request("GET", "/nowhere")->status, 404);
  r = *c->Request("PUT", "/v1/jobs/x");
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(r.Header("allow"), "GET");
  r = *c->Request("DELETE", "/v1/datasets/0000000000000000");
  EXPECT_EQ(r.status, 401);
}

// LAZ and COPC are ingested like LAS; what we do not decode, a cut file and a damaged chunk are
// refused with the reason (the chunk named), and nothing is stored for them.
TEST_F(ServerTest, LazIsIngestedAndBadLazIsRefusedWithTheReason) {
  const auto laz_dir = testing::DataDir() / "laz";
  if (!std::filesystem::exists(laz_dir / "pdal_autzen_trim.laz")) GTEST_SKIP() << laz_dir << " not found; skipping";
  const nlohmann::json copc = Ingest(laz_dir / "pdal_1.2-with-color.copc.laz", "name=copc&voxel=4");
  ASSERT_TRUE(copc.contains("source")) << copc.dump();
  EXPECT_EQ(copc["source"]["points"], 1065);
  EXPECT_EQ(copc["source"]["has_color"], true);
  EXPECT_NE(copc["source"]["compression"].get<std::string>().find("layered, 65 variable chunks"), std::string::npos)
      << copc.dump();
  EXPECT_EQ(copc["source"]["copc"]["nodes"], 65);

  testing::ScratchDir scratch;
  const auto error_of = [](const Response& r) { return Json(r)["error"].get<std::string>(); };
  auto c = daemon_->Connect();
  Response r = *c->Upload("/v1/datasets", laz_dir / "laspy_fullwave.laz", kAuth);
  EXPECT_EQ(r.status, 415);
  EXPECT_NE(error_of(r).find("WAVEPACKET14"), std::string::npos) << r.body;

  const auto bytes = testing::ReadBytes(laz_dir / "pdal_autzen_trim.laz");
  testing::WriteBytes(scratch / "cut.laz", std::vector<uint8_t>(bytes.begin(), bytes.begin() + 300000));
  r = *c->Upload("/v1/datasets", scratch / "cut.laz", kAuth);
  EXPECT_EQ(r.status, 400);
  EXPECT_NE(error_of(r).find("cut short"), std::string::npos) << r.body;

  // Zeros over the end of the first chunk: the header and table are fine, the job fails.
  auto damaged = bytes;
  std::fill(damaged.begin() + 250000, damaged.begin() + 260000, uint8_t{0});
  testing::WriteBytes(scratch / "damaged.laz", damaged);
  r = *c->Upload("/v1/datasets?name=damaged", scratch / "damaged.laz", kAuth);
  ASSERT_EQ(r.status, 202) << r.body;
  const nlohmann::json job = WaitForJob(*c, r.Header("location"));
  EXPECT_EQ(job["status"], "failed") << job.dump();
  EXPECT_NE(job["error"].get<std::string>().find("LAZ chunk 0 of 3 (points 0-49999"), std::string::npos) << job.dump();
  EXPECT_TRUE(job["dataset_id"].is_null());
}

TEST_F(ServerTest, AWrongStoredCrsFailsTheJobAndStoresNothing) {
  SKIP_WITHOUT_DATA();
  auto c = daemon_->Connect();
  const size_t before = Json(*c->Request("GET", "/v1/datasets"))["datasets"].size();
  auto r = c->Upload("/v1/datasets?name=lone", testing::DataDir() / "lone_star_tls_noRGB.las", kAuth);
  ASSERT_EQ(r->status, 202);
  const nlohmann::json job = WaitForJob(*c, r->Header("location"));
  EXPECT_EQ(job["status"], "failed");
  EXPECT_NE(job["error"].get<std::string>().find("geocentric"), std::string::npos) << job.dump();
  EXPECT_TRUE(job["dataset_id"].is_null());
  EXPECT_EQ(Json(*c->Request("GET", "/v1/datasets"))["datasets"].size(), before);
}

TEST_F(ServerTest, TilesAreImmutableWithEtagRangeAndCors) {
  SKIP_WITHOUT_DATA();
  const nlohmann::json meta = Ingest(testing::DataDir() / "tiny_1.2-with-color_1065pts.las", "name=tiny&voxel=10");
  ASSERT_FALSE(meta.is_null());
  auto c = daemon_->Connect();
  const std::string tile = "/v1/datasets/" + meta["id"].get<std::string>() + "/tiles/0/0/0/0";
  const Response full = *c->Request("GET", tile);
  ASSERT_EQ(full.status, 200);
  const std::string etag = full.Header("etag");
  ASSERT_EQ(etag.size(), 18u);  // "16 hex digits", quoted
  EXPECT_EQ(full.Header("cache-control"), "public, max-age=31536000, immutable");
  EXPECT_EQ(full.Header("accept-ranges"), "bytes");
  EXPECT_EQ(full.Header("access-control-allow-origin"), "*");
  EXPECT_NE(full.Header("access-control-expose-headers").find("Content-Range"), std::string::npos);
  EXPECT_TRUE(ParsePdag(std::span(reinterpret_cast<const uint8_t*>(full.body.data()), full.body.size())).ok());

  Response r = *c->Request("GET", tile, {{"If-None-Match", etag}});
  EXPECT_EQ(r.status, 304);
  EXPECT_EQ(r.body, "");
  EXPECT_EQ(r.Header("etag"), etag);
  EXPECT_EQ(c->Request("GET", tile, {{"If-None-Match", "\"other\""}})->status, 200);

  r = *c->Request("GET", tile, {{"Range", "bytes=10-19"}, {"Accept-Encoding", "gzip"}});
  EXPECT_EQ(r.status, 206);
  EXPECT_EQ(r.body, full.body.substr(10, 10));
  EXPECT_EQ(r.Header("content-range"), "bytes 10-19/" + std::to_string(full.body.size()));
  EXPECT_EQ(r.Header("content-encoding"), "");
  r = *c->Request("GET", tile, {{"Range", "bytes=-5"}});
  EXPECT_EQ(r.status, 206);
  EXPECT_EQ(r.body, full.body.substr(full.body.size() - 5));
  r = *c->Request("GET", tile, {{"Range", "bytes=" + std::to_string(full.body.size()) + "-"}});
  EXPECT_EQ(r.status, 416);
  EXPECT_EQ(r.Header("content-range"), "bytes */" + std::to_string(full.body.size()));
  r = *c->Request("GET", tile, {{"Range", "bytes=0-1"}, {"If-Range", "\"stale\""}});
  EXPECT_EQ(r.status, 200);  // If-Range mismatch: the whole tile

  r = *c->Request("OPTIONS", tile, {{"Origin", "https://viewer.example"}, {"Access-Control-Request-Method", "GET"},
                                    {"Access-Control-Request-Headers", "range,if-none-match"}});
  EXPECT_EQ(r.status, 204);
  EXPECT_EQ(r.Header("access-control-allow-origin"), "*");
  EXPECT_NE(r.Header("access-control-allow-headers").find("Range"), std::string::npos);
  EXPECT_NE(r.Header("access-control-allow-headers").find("If-None-Match"), std::string::npos);
  EXPECT_NE(r.Header("access-control-allow-methods").find("GET"), std::string::npos);

  const std::string dataset = "/v1/datasets/" + meta["id"].get<std::string>();
  EXPECT_EQ(c->Request("DELETE", dataset, kAuth)->status, 204);
  EXPECT_EQ(c->Request("GET", dataset)->status, 404);
  EXPECT_EQ(c->Request("GET", tile)->status, 404);  // the cache forgot it too
}

// Every scan with a CRS or without: upload, walk every tile, and compare the finest level with
// `pointdag encode --georeference` of the same file at the same voxel size.
class EveryScanTest : public ServerTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(EveryScanTest, FinestLevelEqualsTheCodecOnTheSameVoxels) {
  SKIP_WITHOUT_DATA();
  const auto scan = testing::DataDir() / GetParam();
  const nlohmann::json meta = Ingest(scan, "name=test");
  ASSERT_FALSE(meta.is_null());
  EXPECT_GT(meta["draco"]["bits_per_point"].get<double>(), 0);
  EXPECT_GT(meta["source"]["points"].get<uint64_t>(), 0u);
  const bool georeferenced = meta["frame"]["georeferenced"].get<bool>();
  if (georeferenced) {
    EXPECT_EQ(meta["frame"]["enu_to_ecef"].size(), 16u);
    EXPECT_TRUE(meta["frame"]["enu_origin"].contains("lat"));
  }
  const std::string url = "http://127.0.0.1:" + std::to_string(daemon_->port()) + "/v1/datasets/" + meta["id"].get<std::string>();
  auto fetched = client::FetchDataset(url, std::nullopt);
  ASSERT_TRUE(fetched.ok()) << fetched.status().ToString();
  size_t tiles = fetched->tiles;
  for (int level = 0; level + 1 < meta["levels"].get<int>(); ++level) {
    auto coarse = client::FetchDataset(url, level);
    ASSERT_TRUE(coarse.ok());
    tiles += coarse->tiles;
    EXPECT_LT(coarse->grid.morton.size(), fetched->grid.morton.size());
  }
  EXPECT_EQ(tiles, meta["tile_count"].get<size_t>());

  EncodeOptions options;
  options.voxel_size = meta["voxel_size"].get<double>();
  options.georeference = true;
  auto encoded = EncodeScan(scan, options);
  ASSERT_TRUE(encoded.ok());
  EXPECT_EQ(fetched->grid.voxel_size, encoded->grid.voxel_size);
  EXPECT_EQ(fetched->grid.origin, encoded->grid.origin);
  ASSERT_EQ(fetched->grid.morton, encoded->grid.morton);
  if (encoded->grid.has_color()) {
    EXPECT_GE(MeasureColorPsnr(encoded->grid.colors, fetched->grid.colors).y, 38.0);
  }
}

INSTANTIATE_TEST_SUITE_P(SharedData, EveryScanTest,
                         ::testing::Values("tiny_1.2-with-color_1065pts.las", "autzen_trim_pdrf3_rgb.las",
                                           "autzen_trim_las14_pdrf7_rgb.las", "ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las",
                                           "lion_takanawa_pdrf7_rgb.las", "pcx_guanyin_cc-by-4.0_rgb.ply",
                                           "pcl_milk_cartoon_clorox_kinect_rgb.ply"), testing::ScanFileName());

int64_t Count(const std::filesystem::path& store, const std::string& sql) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr);
  const int64_t n = sqlite3_step(s) == SQLITE_ROW ? sqlite3_column_int64(s, 0) : -1;
  sqlite3_finalize(s);
  sqlite3_close(db);
  return n;
}

TEST(ServerCrash, KillDuringIngestLeavesNoHalfDatasetAndTheJobResumes) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  Daemon daemon(scratch.path());
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  const std::string location = SubmitScan(*c, "lion_takanawa_pdrf7_rgb.las", "name=lion");
  ASSERT_FALSE(location.empty());
  // Kill it while tiles are being encoded (the longest stage).
  for (int i = 0; i < 400; ++i) {
    const auto job = Json(*c->Request("GET", location));
    if (job["stage"] == "tile") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  daemon.Stop(SIGKILL);
  EXPECT_EQ(Count(daemon.store(), "SELECT COUNT(*) FROM datasets"), 0);
  EXPECT_EQ(Count(daemon.store(), "SELECT COUNT(*) FROM tiles"), 0);
  EXPECT_EQ(Count(daemon.store(), "SELECT COUNT(*) FROM jobs WHERE state = 'running'"), 1);

  ASSERT_TRUE(daemon.Start());
  c = daemon.Connect();
  const nlohmann::json job = WaitForJob(*c, location);
  EXPECT_EQ(job["status"], "done") << job.dump();
  const auto meta = Json(*c->Request("GET", "/v1/datasets/" + job["dataset_id"].get<std::string>()));
  EXPECT_EQ(Count(daemon.store(), "SELECT COUNT(*) FROM tiles"), meta["tile_count"].get<int64_t>());
  EXPECT_EQ(Count(daemon.store(), "SELECT COUNT(*) FROM datasets"), 1);
  // The upload is removed once the dataset is durable, just after the job reads "done".
  const auto uploads = scratch.path() / "var" / "uploads";
  for (int i = 0; i < 100 && !std::filesystem::is_empty(uploads); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(std::filesystem::is_empty(uploads)) << "the upload outlived its job by 5 s";
}

// A POINTDAG_DEVICE the daemon cannot honour stops it at start with the reason (exit code 2).
TEST(Daemon, RefusesToStartOnAnUnknownDevice) {
  const auto dir = std::filesystem::temp_directory_path() / ("pointdagd-device-" + std::to_string(getpid()));
  const std::string command = std::string("env POINTDAG_DEVICE=gpu ") + POINTDAGD + " --listen 127.0.0.1:0 --data-dir " + dir.string() +
                              " >" + (dir.string() + ".log") + " 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const auto log = testing::ReadBytes(dir.string() + ".log");
  EXPECT_NE(std::string(log.begin(), log.end()).find("POINTDAG_DEVICE must be auto, vulkan or cpu, not 'gpu'"), std::string::npos);
  std::filesystem::remove_all(dir);
  std::filesystem::remove(dir.string() + ".log");
}

using testing::ExecSql;

// Waits until the daemon's store says the job is running (its attempt is counted then).
void WaitUntilRunning(Connection& c, const std::string& location) {
  for (int i = 0; i < 1000; ++i) {
    if (Json(*c.Request("GET", location))["status"] == "running") return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  FAIL() << location << " never ran";
}

// A job whose run throws (here: parameters of the wrong type in its stored row, as a damaged or
// foreign store holds them) ends failed with the exception's text; the daemon keeps serving.
TEST(ServerJobs, AJobThatThrowsEndsFailedAndTheDaemonLives) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  Daemon daemon(scratch.path());
  ASSERT_TRUE(daemon.Start());
  daemon.Stop(SIGTERM);
  const auto upload = scratch.path() / "var" / "uploads" / "thrower.upload";
  std::filesystem::copy_file(testing::DataDir() / "tiny_1.2-with-color_1065pts.las", upload);
  ASSERT_TRUE(ExecSql(daemon.store(),
                      "INSERT INTO jobs (id, state, stage, percent, points_in, voxels_out, dataset_id, error, upload_path, "
                      "params, created, updated) VALUES ('00000000000000aa', 'queued', 'queued', 0, 0, 0, '', '', '" +
                          upload.string() + "', '{\"name\": \"x\", \"voxel\": \"ten\"}', 0, 0)"));
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  const nlohmann::json job = WaitForJob(*c, "/v1/jobs/00000000000000aa");
  EXPECT_EQ(job["status"], "failed") << job.dump();
  EXPECT_NE(job.value("error", "").find("Internal: the job threw an exception: [json.exception.type_error.302]"), std::string::npos)
      << job.dump();
  EXPECT_EQ(c->Request("GET", "/livez")->status, 200);
  EXPECT_FALSE(std::filesystem::exists(upload));
  EXPECT_EQ(Count(daemon.store(), "SELECT attempts FROM jobs WHERE id = '00000000000000aa'"), 1);
}

// A job that takes the process down (here: kill -9 while it runs) is run again once, then failed:
// the daemon no longer dies after every restart.
TEST(ServerJobs, AJobInterruptedTwiceIsNotResumedAThirdTime) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  Daemon daemon(scratch.path());
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  const std::string location = SubmitScan(*c, "lion_takanawa_pdrf7_rgb.las", "name=lion");
  ASSERT_FALSE(location.empty());
  for (int crash = 1; crash <= 2; ++crash) {
    WaitUntilRunning(*c, location);
    daemon.Stop(SIGKILL);
    EXPECT_EQ(Count(daemon.store(), "SELECT attempts FROM jobs"), crash);
    ASSERT_TRUE(daemon.Start());
    c = daemon.Connect();
    ASSERT_NE(c, nullptr);
  }
  const nlohmann::json job = WaitForJob(*c, location);
  EXPECT_EQ(job["status"], "failed") << job.dump();
  EXPECT_EQ(job["error"], "interrupted 2 times (the daemon stopped or crashed while running it); not retried");
  EXPECT_EQ(Count(daemon.store(), "SELECT attempts FROM jobs"), 2);
  EXPECT_EQ(Count(daemon.store(), "SELECT COUNT(*) FROM datasets"), 0);
  EXPECT_TRUE(std::filesystem::is_empty(scratch.path() / "var" / "uploads"));
  EXPECT_EQ(c->Request("GET", "/livez")->status, 200);
}

// A store written before jobs.attempts existed opens, keeps its jobs and gains the column.
TEST(ServerJobs, AStoreWithoutTheAttemptsColumnIsMigrated) {
  testing::ScratchDir scratch;
  std::filesystem::create_directories(scratch.path() / "var");
  const auto store = scratch.path() / "var" / "store.sqlite";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(store.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "CREATE TABLE jobs (id TEXT PRIMARY KEY, state TEXT NOT NULL, stage TEXT NOT NULL, percent REAL NOT "
                         "NULL, points_in INTEGER NOT NULL, voxels_out INTEGER NOT NULL, dataset_id TEXT NOT NULL, error TEXT "
                         "NOT NULL, upload_path TEXT NOT NULL, params TEXT NOT NULL, created REAL NOT NULL, updated REAL NOT NULL);"
                         "INSERT INTO jobs VALUES ('00000000000000bb', 'failed', 'survey', 5, 0, 0, '', 'old reason', '', '{}', 1, 2);",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  Daemon daemon(scratch.path());
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  ASSERT_NE(c, nullptr);
  const nlohmann::json job = Json(*c->Request("GET", "/v1/jobs/00000000000000bb"));
  EXPECT_EQ(job["status"], "failed");
  EXPECT_EQ(job["error"], "old reason");
  EXPECT_EQ(Count(daemon.store(), "SELECT attempts FROM jobs WHERE id = '00000000000000bb'"), 0);
}

// Invalid UTF-8 in the name: a valid JSON answer (U+FFFD in place of the byte), and a dataset.
// `pointdag bench --server`: each scan uploaded twice with the write token, a row of figures per
// scan, and the benchmark's datasets deleted again.
TEST_F(ServerTest, UploadBenchReportsEndToEndAndLeavesNoDataset) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir dir;
  std::filesystem::create_directories(dir / "scans");
  std::filesystem::copy_file(testing::DataDir() / "tiny_1.2-with-color_1065pts.las", dir / "scans" / "tiny.las");
  auto c = daemon_->Connect();
  const auto count = [&] {
    auto listed = c->Request("GET", "/v1/datasets", kAuth);
    EXPECT_TRUE(listed.ok());
    return Json(*listed)["datasets"].size();
  };
  const size_t before = count();
  const std::string url = "http://127.0.0.1:" + std::to_string(daemon_->port());
  const auto run = testing::Cli("bench --server " + url + " --data " + (dir / "scans").string() + " --json", dir,
                                std::string("POINTDAGD_TOKEN=") + kToken);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json row = nlohmann::json::parse(run.out);
  EXPECT_EQ(row["scan"], "tiny.las");
  EXPECT_EQ(row["points"], 1065);
  EXPECT_EQ(row["voxel"], 100);
  EXPECT_GT(row["end_to_end_s"].get<double>(), row["daemon_ingest_s"].get<double>());
  EXPECT_GT(row["daemon_ingest_s"].get<double>(), 0);
  EXPECT_EQ(count(), before);
  // Without the token the daemon refuses the upload, and the bench says so.
  const auto refused = testing::Cli("bench --server " + url + " --data " + (dir / "scans").string(), dir);
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("got 401"), std::string::npos) << refused.err;
}

TEST_F(ServerTest, InvalidUtf8InTheNameGivesValidJson) {
  SKIP_WITHOUT_DATA();
  auto c = daemon_->Connect();
  auto r = c->Upload("/v1/datasets?name=a%FFb&voxel=10", testing::DataDir() / "tiny_1.2-with-color_1065pts.las", kAuth);
  ASSERT_EQ(r->status, 202);
  const nlohmann::json accepted = Json(*r);
  ASSERT_FALSE(accepted.is_discarded()) << r->body;
  EXPECT_EQ(accepted["params"]["name"], "a\xEF\xBF\xBD" "b");
  const nlohmann::json job = WaitForJob(*c, r->Header("location"));
  ASSERT_EQ(job["status"], "done") << job.dump();
  EXPECT_EQ(Json(*c->Request("GET", "/v1/datasets/" + job["dataset_id"].get<std::string>()))["name"], "a\xEF\xBF\xBD" "b");
}

// If-None-Match: a `*` inside a tag is not the wildcard; `Bearer` in any case is the scheme.
TEST_F(ServerTest, StarInsideATagIsNoWildcardAndBearerIsCaseInsensitive) {
  SKIP_WITHOUT_DATA();
  const nlohmann::json meta = Ingest(testing::DataDir() / "tiny_1.2-with-color_1065pts.las", "name=star&voxel=10");
  ASSERT_FALSE(meta.is_null());
  auto c = daemon_->Connect();
  const std::string dataset = "/v1/datasets/" + meta["id"].get<std::string>();
  EXPECT_EQ(c->Request("GET", dataset + "/tiles/0/0/0/0", {{"If-None-Match", "\"a*b\""}})->status, 200);
  EXPECT_EQ(c->Request("GET", dataset + "/tiles/0/0/0/0", {{"If-None-Match", "*"}})->status, 304);
  EXPECT_EQ(c->Request("DELETE", dataset, {{"Authorization", std::string("bearer ") + kToken}})->status, 204);
}

}  // namespace
}  // namespace pointdag
