// The API's rules as Service::Handle applies them (the function the daemon's transport calls for
// every request), over a real store in a scratch folder: token scopes, CORS, conditional requests,
// the tile cache against DELETE. Configurations the daemon's flags do not reach yet are tested here.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "jobs.h"
#include "metrics.h"
#include "service.h"
#include "store.h"
#include "test_util.h"

namespace pointdag::server {
namespace {

constexpr const char* kDataset = "d000000000000001";
constexpr const char* kTile = "/v1/datasets/d000000000000001/tiles/0/0/0/0";

// A store holding one dataset with one tile, and a service over it configured by the test.
class ServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto opened = Store::Open(scratch_ / "store.sqlite");
    ASSERT_TRUE(opened.ok()) << opened.status().ToString();
    store_ = std::move(*opened);
    JobRecord job;
    job.id = "j000000000000001";
    ASSERT_TRUE(store_->CreateJob(job).ok());
    TileSet tiles;
    tiles.levels = 1;
    tiles.tiles.push_back({TileKey{0, 0, 0, 0}, 1, {1, 2, 3, 4, 5}});
    ASSERT_TRUE(store_->CommitDataset(job.id, kDataset, "one", {{"id", kDataset}, {"tile_count", 1}}, tiles).ok());
    jobs_ = std::make_unique<JobQueue>(*store_, metrics_, JobLimits{});
  }
  Service Make(ServiceConfig config) { return Service(*store_, *jobs_, metrics_, std::move(config)); }
  static HttpRequest Get(const std::string& target, std::map<std::string, std::string> headers = {}) {
    return HttpRequest{"GET", target, std::move(headers), ""};
  }
  static std::string HeaderOf(const HttpResponse& r, const std::string& name) {
    for (const auto& [n, v] : r.headers) {
      if (n == name) return v;
    }
    return "";
  }

  testing::ScratchDir scratch_;
  std::unique_ptr<Store> store_;
  Metrics metrics_;
  std::unique_ptr<JobQueue> jobs_;
};

ServiceConfig Scoped(bool require_token_for_reads) {
  ServiceConfig c;
  c.token = "write-secret";
  c.read_token = "read-secret";
  c.require_token_for_reads = require_token_for_reads;
  return c;
}

TEST_F(ServiceTest, TheReadTokenReadsButCannotWrite) {
  Service service = Make(Scoped(false));
  const HttpRequest del{"DELETE", "/v1/datasets/0000000000000000", {{"authorization", "Bearer read-secret"}}, ""};
  const HttpResponse r = service.Handle(del);
  EXPECT_EQ(r.status, 403);
  EXPECT_NE(r.body.find("this token may only read"), std::string::npos) << r.body;
  const HttpRequest upload{"POST", "/v1/datasets", {{"authorization", "Bearer read-secret"}, {"content-length", "10"}}, ""};
  EXPECT_EQ(service.AdmitUpload(upload)->status, 403);
  // Reads are open unless require_token_for_reads.
  EXPECT_EQ(service.Handle(Get(kTile)).status, 200);
  EXPECT_EQ(service.Handle(Get(kTile, {{"authorization", "Bearer read-secret"}})).status, 200);
  // The write token writes.
  EXPECT_EQ(service.Handle({"DELETE", "/v1/datasets/0000000000000000", {{"authorization", "Bearer write-secret"}}, ""}).status, 404);
}

TEST_F(ServiceTest, RequireTokenForReadsGuardsEveryReadButHealth) {
  Service service = Make(Scoped(true));
  service.set_ready(true);
  for (const std::string& target : {std::string(kTile), std::string("/v1/datasets"), std::string("/v1/datasets/") + kDataset,
                                   std::string("/v1/datasets/") + kDataset + "/hierarchy/0/0/0/0",
                                   std::string("/v1/jobs/j000000000000001"), std::string("/metrics")}) {
    const HttpResponse none = service.Handle(Get(target));
    EXPECT_EQ(none.status, 401) << target;
    EXPECT_EQ(HeaderOf(none, "WWW-Authenticate"), "Bearer") << target;
    EXPECT_EQ(service.Handle(Get(target, {{"authorization", "Bearer wrong"}})).status, 401) << target;
    EXPECT_EQ(service.Handle(Get(target, {{"authorization", "Bearer read-secret"}})).status, 200) << target;
    EXPECT_EQ(service.Handle(Get(target, {{"authorization", "Bearer write-secret"}})).status, 200) << target;
  }
  EXPECT_EQ(service.Handle(Get("/livez")).status, 200);
  EXPECT_EQ(service.Handle(Get("/readyz")).status, 200);
  EXPECT_EQ(service.Handle({"OPTIONS", kTile, {}, ""}).status, 204);
}

TEST_F(ServiceTest, ShadowRoutesFollowTheTokenScopesAndAFailedJobStoresNothing) {
  Service service = Make(Scoped(true));
  const std::string shadows = std::string("/v1/datasets/") + kDataset + "/shadows";
  const std::map<std::string, std::string> reader{{"authorization", "Bearer read-secret"}}, writer{{"authorization", "Bearer write-secret"}};
  for (const std::string& target : {shadows, shadows + "/tiles/0/0/0/0"}) {
    EXPECT_EQ(service.Handle(Get(target)).status, 401) << target;
    const HttpResponse r = service.Handle(Get(target, reader));
    EXPECT_EQ(r.status, 404) << target;  // allowed to read: the dataset has no shadows
    EXPECT_EQ(r.route, target == shadows ? "/v1/datasets/{id}/shadows" : "/v1/datasets/{id}/shadows/tiles");
  }
  const std::string body = R"({"direction": [0, 0, -1]})";
  EXPECT_EQ(service.Handle({"POST", shadows, reader, body}).status, 403);
  EXPECT_EQ(service.Handle({"DELETE", shadows, reader, ""}).status, 403);
  EXPECT_EQ(service.Handle({"POST", shadows, {}, body}).status, 401);
  EXPECT_EQ(service.Handle({"POST", shadows, {{"authorization", "Bearer a, Bearer b"}}, body}).status, 400);
  // The fixture's dataset has no frame: a time is refused, asking for a direction.
  const HttpResponse time = service.Handle({"POST", shadows, writer, R"({"time": "2026-06-21T12:00:00Z"})"});
  EXPECT_EQ(time.status, 400);
  EXPECT_NE(time.body.find("give a direction"), std::string::npos) << time.body;
  // Its tile is no .pdag, so the job fails; nothing is stored.
  const HttpResponse posted = service.Handle({"POST", shadows, writer, body});
  ASSERT_EQ(posted.status, 202) << posted.body;
  const std::string job = HeaderOf(posted, "Location");
  std::string state;
  for (int i = 0; i < 200 && state != "failed" && state != "done"; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    state = nlohmann::json::parse(service.Handle(Get(job, reader)).body)["status"];
  }
  EXPECT_EQ(state, "failed");
  const nlohmann::json ended = nlohmann::json::parse(service.Handle(Get(job, reader)).body);
  EXPECT_EQ(ended["kind"], "shadows");
  EXPECT_EQ(ended["error"], "Corrupt: the dataset's metadata lacks depth");
  EXPECT_EQ(service.Handle(Get(shadows, reader)).status, 404);
}

TEST_F(ServiceTest, BearerIsCaseInsensitiveAndOnlyTheWholeTokenMatches) {
  Service service = Make(Scoped(true));
  EXPECT_EQ(service.Handle(Get(kTile, {{"authorization", "bearer read-secret"}})).status, 200);
  EXPECT_EQ(service.Handle(Get(kTile, {{"authorization", "BEARER read-secret"}})).status, 200);
  // Prefixes and extensions of a token, and another scheme, are refused.
  for (const char* wrong : {"Bearer read-secre", "Bearer read-secret0", "Bearer ", "Basic read-secret", "read-secret"}) {
    EXPECT_EQ(service.Handle(Get(kTile, {{"authorization", wrong}})).status, 401) << wrong;
  }
}

TEST_F(ServiceTest, SeveralAuthorizationHeadersAre400) {
  Service service = Make(Scoped(false));
  // The transport joins repeated fields with ", ": neither the first nor the last may win.
  for (const char* joined : {"Bearer read-secret, Bearer write-secret", "Bearer write-secret, Bearer read-secret"}) {
    const HttpResponse r = service.Handle({"DELETE", std::string("/v1/datasets/") + kDataset, {{"authorization", joined}}, ""});
    EXPECT_EQ(r.status, 400) << joined;
    EXPECT_NE(r.body.find("one Authorization header"), std::string::npos) << r.body;
  }
  EXPECT_EQ(service.Handle(Get(std::string("/v1/datasets/") + kDataset)).status, 200);  // not deleted
}

TEST_F(ServiceTest, CorsEchoesOnlyListedOrigins) {
  ServiceConfig config;
  config.cors_origins = {"https://a.example", "https://b.example"};
  Service service = Make(config);
  HttpResponse r = service.Handle(Get(kTile, {{"origin", "https://b.example"}}));
  EXPECT_EQ(HeaderOf(r, "Access-Control-Allow-Origin"), "https://b.example");
  EXPECT_EQ(HeaderOf(r, "Vary"), "Origin");
  EXPECT_NE(HeaderOf(r, "Access-Control-Expose-Headers").find("ETag"), std::string::npos);
  r = service.Handle(Get(kTile, {{"origin", "https://evil.example"}}));
  EXPECT_EQ(HeaderOf(r, "Access-Control-Allow-Origin"), "");
  EXPECT_EQ(HeaderOf(r, "Vary"), "Origin");
  r = service.Handle({"OPTIONS", kTile, {{"origin", "https://a.example"}}, ""});
  EXPECT_EQ(HeaderOf(r, "Access-Control-Allow-Origin"), "https://a.example");
  EXPECT_EQ(HeaderOf(service.Handle(Get("/nowhere", {{"origin", "https://a.example"}})), "Access-Control-Allow-Origin"),
            "https://a.example");  // errors too

  Service any = Make(ServiceConfig{});
  r = any.Handle(Get(kTile, {{"origin", "https://evil.example"}}));
  EXPECT_EQ(HeaderOf(r, "Access-Control-Allow-Origin"), "*");
  EXPECT_EQ(HeaderOf(r, "Vary"), "");
}

TEST_F(ServiceTest, OnlyAWholeValueStarMatchesIfNoneMatch) {
  Service service = Make(ServiceConfig{});
  const std::string etag = HeaderOf(service.Handle(Get(kTile)), "ETag");
  EXPECT_EQ(service.Handle(Get(kTile, {{"if-none-match", "\"a*b\""}})).status, 200);
  EXPECT_EQ(service.Handle(Get(kTile, {{"if-none-match", "\"x\", *"}})).status, 200);
  EXPECT_EQ(service.Handle(Get(kTile, {{"if-none-match", " * "}})).status, 304);
  EXPECT_EQ(service.Handle(Get(kTile, {{"if-none-match", "\"x\", " + etag}})).status, 304);
}

TEST_F(ServiceTest, WithoutAViewerTheRootSaysHowToGetOne) {
  Service service = Make(ServiceConfig{});
  const HttpResponse r = service.Handle(Get("/"));
  EXPECT_EQ(r.status, 404);
  EXPECT_NE(r.body.find("the web viewer is not installed in this daemon"), std::string::npos) << r.body;
  EXPECT_EQ(service.Handle(Get("/datasets/d000000000000001")).status, 404);
}

TEST_F(ServiceTest, TheViewerDoesNotShadowTheApi) {
  std::filesystem::create_directories(scratch_ / "web/assets");
  std::ofstream(scratch_ / "web/index.html") << "<!doctype html>";
  auto web = WebFiles::Load(scratch_ / "web");
  ASSERT_TRUE(web.ok()) << web.status().ToString();
  ServiceConfig config;
  config.web = std::make_shared<const WebFiles>(std::move(*web));
  Service service = Make(config);
  EXPECT_EQ(service.Handle(Get("/")).body, "<!doctype html>");
  EXPECT_EQ(service.Handle(Get("/datasets/d000000000000001")).body, "<!doctype html>");
  const HttpResponse api = service.Handle(Get("/v1/datasets/d000000000000001"));
  EXPECT_EQ(api.status, 200);
  EXPECT_NE(api.body.find("\"tile_count\""), std::string::npos);
  EXPECT_EQ(service.Handle(HttpRequest{"POST", "/", {}, ""}).status, 404);
}

TEST(TileCache, ATileReadBeforeAnEraseIsNotCachedAfterIt) {
  TileCache cache(1 << 20);
  auto tile = std::make_shared<const StoredTile>(StoredTile{"\"e\"", {1, 2, 3}});
  const uint64_t read_at = cache.generation();  // a GET misses and reads the store ...
  cache.EraseDataset("d1");                      // ... a DELETE of the dataset completes ...
  cache.Put("d1/0/0/0/0", tile, read_at);        // ... and the GET's tile must not come back
  EXPECT_EQ(cache.Get("d1/0/0/0/0"), nullptr);
  cache.Put("d1/0/0/0/0", tile, cache.generation());
  EXPECT_NE(cache.Get("d1/0/0/0/0"), nullptr);
}

}  // namespace
}  // namespace pointdag::server
