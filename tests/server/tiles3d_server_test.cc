// 3D Tiles from a real pointdagd on loopback: GET .../3dtiles/tileset.json and .../{l}/{x}/{y}/{z}.glb
// answered as tiles are (ETag, 304, Range, CORS, tokens, 404/400, DELETE), their bytes equal to
// the codec's transcoding of the served tiles, and `pointdag export URL --3dtiles` equal to them.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <functional>
#include <set>
#include <thread>

#include "client.h"
#include "daemon_util.h"
#include "pointdag/tiles3d/tile_content.h"
#include "store.h"
#include "test_util.h"

namespace pointdag {
namespace {

using client::Response;

std::span<const uint8_t> Bytes(const std::string& s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

// Every content uri a tileset names, depth first.
std::vector<std::string> ContentUris(const nlohmann::json& tileset) {
  std::vector<std::string> out;
  const std::function<void(const nlohmann::json&)> walk = [&](const nlohmann::json& tile) {
    out.push_back(tile["content"]["uri"]);
    if (tile.contains("children")) {
      for (const nlohmann::json& child : tile["children"]) walk(child);
    }
  };
  walk(tileset["root"]);
  return out;
}

class Tiles3dServer : public ::testing::Test {
 protected:
  // One daemon for the suite, started by its first test (SuiteDaemon says why).
  void SetUp() override { ASSERT_TRUE(daemon_.Start()) << "the suite's pointdagd did not start"; }
  static void TearDownTestSuite() { daemon_.Stop(); }
  // Uploads a scan of ../shared/data and waits for its dataset; "" with a failure when it fails.
  static std::string Ingest(const std::string& scan, const std::string& query) {
    return IngestScan(*daemon_->Connect(), scan, query);
  }
  // Autzen at 0.5 m: three levels, georeferenced; ingested once for the suite.
  static const std::string& Autzen() {
    static const std::string dataset = Ingest("autzen_trim_pdrf3_rgb.las", "name=autzen&voxel=0.5");
    return dataset;
  }
  static inline SuiteDaemon daemon_{"pointdagd-tiles3d-test"};
};

// 200 with the immutable-caching headers and an ETag that is the bytes' XXH3; then 304 for it.
void ExpectImmutable(client::Connection& c, const std::string& target, const Response& r, const std::string& type) {
  SCOPED_TRACE(target);
  EXPECT_EQ(r.status, 200) << r.body.substr(0, 200);
  EXPECT_EQ(r.Header("content-type"), type);
  EXPECT_EQ(r.Header("etag"), server::TileEtag(Bytes(r.body)));
  EXPECT_EQ(r.Header("cache-control"), "public, max-age=31536000, immutable");
  EXPECT_EQ(r.Header("access-control-allow-origin"), "*");
  const Response again = *c.Request("GET", target, {{"If-None-Match", r.Header("etag")}});
  EXPECT_EQ(again.status, 304);
  EXPECT_EQ(again.body, "");
  EXPECT_EQ(again.Header("etag"), r.Header("etag"));
}

TEST_F(Tiles3dServer, TilesetAndContentsAreTheTranscodedTilesServedImmutably) {
  SKIP_WITHOUT_DATA();
  const std::string dataset = Autzen();
  ASSERT_FALSE(dataset.empty());
  auto c = daemon_->Connect();
  const nlohmann::json meta = Json(*c->Request("GET", dataset));
  ASSERT_GE(meta["levels"].get<int>(), 3);
  const std::string tileset_target = dataset + "/3dtiles/tileset.json";
  const Response tileset = *c->Request("GET", tileset_target, {{"Origin", "https://viewer.example"}});
  ExpectImmutable(*c, tileset_target, tileset, "application/json");
  EXPECT_EQ(c->Request("GET", tileset_target)->body, tileset.body);  // from the cache: the same bytes
  const Response part = *c->Request("GET", tileset_target, {{"Range", "bytes=0-9"}});
  EXPECT_EQ(part.status, 206);
  EXPECT_EQ(part.body, tileset.body.substr(0, 10));

  // The tileset is the codec's, from the dataset's description and its served tiles' boxes; each
  // content is the codec's transcoding of the served tile.
  const auto described = ParseTilesetDataset(meta);
  ASSERT_TRUE(described.ok()) << described.status().ToString();
  const nlohmann::json parsed = nlohmann::json::parse(tileset.body);
  EXPECT_EQ(parsed["root"]["transform"], meta["frame"]["enu_to_ecef"]);
  const std::vector<std::string> uris = ContentUris(parsed);
  EXPECT_EQ(uris.size(), meta["tile_count"].get<size_t>());
  std::vector<TileBox> boxes;
  for (const std::string& uri : uris) {
    TileKey key;
    ASSERT_EQ(std::sscanf(uri.c_str(), "%d/%u/%u/%u.glb", &key.level, &key.x, &key.y, &key.z), 4) << uri;
    const Response stored = *c->Request("GET", dataset + "/tiles/" + uri.substr(0, uri.size() - 4));
    ASSERT_EQ(stored.status, 200);
    const auto expected = TranscodeTile(key, Bytes(stored.body), described->tile_depth);
    ASSERT_TRUE(expected.ok()) << expected.status().ToString();
    boxes.push_back(expected->box);
    const std::string target = dataset + "/3dtiles/" + uri;
    const Response glb = *c->Request("GET", target);
    ExpectImmutable(*c, target, glb, "model/gltf-binary");
    EXPECT_EQ(glb.body, std::string(expected->glb.begin(), expected->glb.end())) << uri;
  }
  EXPECT_EQ(tileset.body, *BuildTileset(*described, boxes));

  const Response metrics = *c->Request("GET", "/metrics");
  EXPECT_NE(metrics.body.find("pointdag_http_requests_total{route=\"/v1/datasets/{id}/3dtiles\",status=\"200\"} "),
            std::string::npos);
  EXPECT_NE(metrics.body.find("pointdag_http_requests_total{route=\"/v1/datasets/{id}/3dtiles\",status=\"304\"} "),
            std::string::npos);
}

TEST_F(Tiles3dServer, ExportFromTheUrlWritesTheServedBytes) {
  SKIP_WITHOUT_DATA();
  const std::string dataset = Autzen();
  ASSERT_FALSE(dataset.empty());
  testing::ScratchDir scratch;
  const std::string url = "http://127.0.0.1:" + std::to_string(daemon_->port()) + dataset;
  const std::string command = std::string(POINTDAG_CLI) + " export " + url + " --3dtiles " + (scratch / "out").string() + " 2>" +
                              (scratch / "err").string();
  const int status = std::system(command.c_str());
  const auto err = testing::ReadBytes(scratch / "err");
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << std::string(err.begin(), err.end());

  auto c = daemon_->Connect();
  const Response tileset = *c->Request("GET", dataset + "/3dtiles/tileset.json");
  ASSERT_EQ(tileset.status, 200);
  const auto written = testing::ReadBytes(scratch / "out" / "tileset.json");
  EXPECT_EQ(std::string(written.begin(), written.end()), tileset.body);
  std::set<std::string> expected_files = {"tileset.json"}, files;
  for (const std::string& uri : ContentUris(nlohmann::json::parse(tileset.body))) {
    expected_files.insert(uri);
    const Response glb = *c->Request("GET", dataset + "/3dtiles/" + uri);
    ASSERT_EQ(glb.status, 200);
    const auto bytes = testing::ReadBytes(scratch / "out" / uri);
    EXPECT_EQ(std::string(bytes.begin(), bytes.end()), glb.body) << uri;
  }
  for (const auto& entry : std::filesystem::recursive_directory_iterator(scratch / "out")) {
    if (entry.is_regular_file()) files.insert(std::filesystem::relative(entry.path(), scratch / "out").string());
  }
  EXPECT_EQ(files, expected_files);
}

TEST_F(Tiles3dServer, UnknownIs404MalformedIs400WrongMethodIs405) {
  SKIP_WITHOUT_DATA();
  const std::string dataset = Autzen();
  ASSERT_FALSE(dataset.empty());
  auto c = daemon_->Connect();
  const auto error_of = [](const Response& r) { return Json(r)["error"].get<std::string>(); };
  Response r = *c->Request("GET", "/v1/datasets/0000000000000000/3dtiles/tileset.json");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(error_of(r), "no dataset 0000000000000000");
  EXPECT_EQ(r.Header("access-control-allow-origin"), "*");
  r = *c->Request("GET", "/v1/datasets/0000000000000000/3dtiles/0/0/0/0.glb");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(error_of(r), "no dataset 0000000000000000");
  r = *c->Request("GET", dataset + "/3dtiles/0/0/0/1.glb");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(error_of(r), "no tile 0/0/0/1 in this dataset");
  for (const char* bad : {"0/0/0/zero.glb", "0/0/0/0", "0/0/0/0.gltf", "22/0/0/0.glb", "0/0/0.glb", "tileset.xml", "0/0/0/0/0.glb", ""}) {
    r = *c->Request("GET", dataset + "/3dtiles/" + bad);
    EXPECT_EQ(r.status, 400) << bad;
    EXPECT_NE(error_of(r).find("tileset.json"), std::string::npos) << bad;
  }
  r = *c->Request("POST", dataset + "/3dtiles/tileset.json", kAuth);
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(r.Header("allow"), "GET");
}

TEST_F(Tiles3dServer, DeleteDropsTheTilesetAndContents) {
  SKIP_WITHOUT_DATA();
  const std::string dataset = Ingest("tiny_1.2-with-color_1065pts.las", "name=tiny&voxel=2");
  ASSERT_FALSE(dataset.empty());
  auto c = daemon_->Connect();
  ASSERT_EQ(c->Request("GET", dataset + "/3dtiles/tileset.json")->status, 200);  // now cached
  ASSERT_EQ(c->Request("GET", dataset + "/3dtiles/0/0/0/0.glb")->status, 200);
  EXPECT_EQ(c->Request("DELETE", dataset)->status, 401);  // DELETE needs the write token, as ever
  EXPECT_EQ(c->Request("DELETE", dataset, kAuth)->status, 204);
  EXPECT_EQ(c->Request("GET", dataset + "/3dtiles/tileset.json")->status, 404);
  EXPECT_EQ(c->Request("GET", dataset + "/3dtiles/0/0/0/0.glb")->status, 404);
}

TEST_F(Tiles3dServer, ConcurrentFirstReadsOfADatasetAgree) {
  SKIP_WITHOUT_DATA();
  // A dataset nobody has read yet: every thread misses the cache and transcodes on its own.
  const std::string dataset = Ingest("autzen_trim_las14_pdrf7_rgb.las", "name=concurrent&voxel=1");
  ASSERT_FALSE(dataset.empty());
  const std::vector<std::string> targets = {dataset + "/3dtiles/tileset.json", dataset + "/3dtiles/0/0/0/0.glb",
                                            dataset + "/3dtiles/1/0/0/0.glb"};
  std::vector<std::vector<Response>> answers(4);
  std::vector<std::thread> threads;
  for (auto& mine : answers) {
    threads.emplace_back([&] {
      auto c = daemon_->Connect();
      for (const std::string& t : targets) mine.push_back(*c->Request("GET", t));
    });
  }
  for (auto& t : threads) t.join();
  for (size_t i = 0; i < targets.size(); ++i) {
    EXPECT_EQ(answers[0][i].status, 200) << targets[i];
    for (const auto& other : answers) EXPECT_EQ(other[i].body, answers[0][i].body) << targets[i];
  }
}

// Reads that need a token: the 3D Tiles routes follow the tiles' rules.
TEST(Tiles3dTokens, ReadsNeedTheReadOrWriteTokenWhenTheDaemonSaysSo) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  std::ofstream(scratch / "pointdagd.toml") << "read_token = \"reader\"\nrequire_token_for_reads = true\n";
  Daemon daemon(scratch.path(), {"--config", (scratch / "pointdagd.toml").string()});
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  const std::string location = SubmitScan(*c, "tiny_1.2-with-color_1065pts.las", "name=tiny&voxel=2");
  ASSERT_FALSE(location.empty());
  nlohmann::json job = nlohmann::json::object();
  for (int i = 0; i < 600 && job.value("status", "") != "done" && job.value("status", "") != "failed"; ++i) {
    job = Json(*c->Request("GET", location, kAuth));
    usleep(100000);
  }
  ASSERT_EQ(job["status"], "done") << job.dump();
  const std::string base = "/v1/datasets/" + job["dataset_id"].get<std::string>() + "/3dtiles/";
  for (const std::string& target : {base + "tileset.json", base + "0/0/0/0.glb"}) {
    SCOPED_TRACE(target);
    Response r = *c->Request("GET", target);
    EXPECT_EQ(r.status, 401);
    EXPECT_EQ(r.Header("www-authenticate"), "Bearer");
    EXPECT_EQ(r.Header("access-control-allow-origin"), "*");
    EXPECT_EQ(c->Request("GET", target, {{"Authorization", "Bearer wrong"}})->status, 401);
    EXPECT_EQ(c->Request("GET", target, {{"Authorization", "Bearer reader, Bearer reader"}})->status, 400);
    EXPECT_EQ(c->Request("GET", target, {{"Authorization", "Bearer reader"}})->status, 200);
    EXPECT_EQ(c->Request("GET", target, kAuth)->status, 200);
    // A browser's preflight carries no token and is answered.
    EXPECT_EQ(c->Request("OPTIONS", target, {{"Origin", "https://viewer.example"}, {"Access-Control-Request-Method", "GET"}})->status, 204);
  }
}

}  // namespace
}  // namespace pointdag
