// The shadow DAG a one-light shadow set keeps (proto/PROTOCOL.md §3.2), from a real pointdagd on
// loopback: served as bytes, asked point by point (exact at every finest voxel against
// ShadowedVoxels, with a bias), replaced and deleted with its set, bad queries, an older store
// without the table, and pointdagd --check reading the stored bytes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "client.h"
#include "daemon_util.h"
#include "pointdag/dag/dag_builder.h"
#include "pointdag/shadow/shadow_dag.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/morton.h"
#include "shadow_test_util.h"
#include "store.h"
#include "store_util.h"
#include "test_util.h"

namespace pointdag {
namespace {

using client::Response;

class ShadowQuery : public ShadowSuite<ShadowQuery> {
 public:
  static constexpr const char* kDaemonName = "pointdagd-shadow-query-test";
};

// The set's shadow DAG (for one light): stored with the layers, served as bytes, and asked point by
// point; every finest voxel's centre answers its exact shadow (with the set's bias), through the
// route and through the served bytes; replaced and deleted with the set; bad queries are 400.
TEST_F(ShadowQuery, TheShadowDagIsServedAndQueriedExactly) {
  const std::string autzen = Ingest("autzen_trim_pdrf3_rgb.las", "name=autzen&voxel=4");
  ASSERT_FALSE(autzen.empty());
  const std::string id = autzen.substr(std::string("/v1/datasets/").size());
  auto c = daemon_->Connect();
  const nlohmann::json meta = Json(*c->Request("GET", autzen));
  Response r = *c->Request("GET", autzen + "/shadows/dag");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(ErrorOf(r), "dataset " + id + " has no shadows (POST /v1/datasets/" + id + "/shadows computes them)");
  r = *c->Request("GET", autzen + "/shadows/query?x=0&y=0&z=0");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(ErrorOf(r), "dataset " + id + " has no shadows (POST /v1/datasets/" + id + "/shadows computes them)");
  EXPECT_EQ(ErrorOf(*c->Request("GET", "/v1/datasets/0000000000000000/shadows/query?x=0&y=0&z=0")), "no dataset 0000000000000000");
  for (const char* bias : {"-1", "16.5", "\"1\"", "null", "[1]"}) {
    r = Post(*c, autzen + "/shadows", std::string(R"({"direction": [0, 0, -1], "bias": )") + bias + "}");
    EXPECT_EQ(r.status, 400) << bias;
    EXPECT_EQ(ErrorOf(r), "bias must be a number of voxels from 0 to 16 (the self-shadow bias; 0 is the exact definition)") << bias;
  }

  const auto finest = client::FetchDataset("http://127.0.0.1:" + std::to_string(daemon_->port()) + autzen, std::nullopt);
  ASSERT_TRUE(finest.ok()) << finest.status().ToString();
  const auto dag = BuildDag(finest->grid.morton, finest->grid.depth);
  ASSERT_TRUE(dag.ok());
  const std::array<double, 3> origin{meta["bounds"]["min"][0].get<double>(), meta["bounds"]["min"][1].get<double>(),
                                     meta["bounds"]["min"][2].get<double>()};
  const double voxel = meta["voxel_size"].get<double>();
  // Every finest voxel's centre, asked of the daemon and of the served DAG, against ShadowedVoxels.
  const auto expect_exact = [&](double bias, const std::string& what) {
    SCOPED_TRACE(what);
    Light light = *LightFromDirection(1, 0.5, -0.6);
    light.bias_voxels = bias;
    const auto exact = ShadowedVoxels(*dag, light);
    ASSERT_TRUE(exact.ok()) << exact.status().ToString();
    const nlohmann::json summary = Json(*c->Request("GET", autzen + "/shadows"));
    EXPECT_EQ(summary["bias"].get<double>(), bias);
    const auto dark = static_cast<uint64_t>(std::count(exact->begin(), exact->end(), 1));
    EXPECT_EQ(summary["shadowed_voxels"].get<uint64_t>(), dark);
    EXPECT_GT(dark, 100u);  // both answers are common: the comparison is not trivial
    EXPECT_GT(exact->size() - dark, 100u);
    const Response bytes = *c->Request("GET", autzen + "/shadows/dag");
    ASSERT_EQ(bytes.status, 200);
    EXPECT_EQ(bytes.Header("content-type"), "application/vnd.pointdag.shadow-dag");
    EXPECT_EQ(bytes.Header("etag"), server::TileEtag(Bytes(bytes.body)));
    EXPECT_EQ(bytes.Header("cache-control"), "no-cache");
    EXPECT_EQ(c->Request("GET", autzen + "/shadows/dag", {{"If-None-Match", bytes.Header("etag")}})->status, 304);
    const auto served = ShadowDag::Deserialize(Bytes(bytes.body));
    ASSERT_TRUE(served.ok()) << served.status().ToString();
    const auto fetched = client::FetchShadowDag(*c, autzen);  // the C++ client reads the same bytes
    ASSERT_TRUE(fetched.ok()) << fetched.status().ToString();
    EXPECT_EQ(fetched->Serialize(), std::vector<uint8_t>(bytes.body.begin(), bytes.body.end()));
    EXPECT_EQ(summary["shadow_dag_bytes"].get<uint64_t>(), served->stats().shadow_dag_bytes);
    EXPECT_EQ(summary["shadow_dag_file_bytes"].get<uint64_t>(), bytes.body.size());
    EXPECT_EQ(summary["dense_grid_bytes"].get<uint64_t>(), served->stats().dense_grid_bytes);
    EXPECT_EQ(summary["shadow_map_bytes"].get<uint64_t>(), served->stats().shadow_map_bytes);
    EXPECT_EQ(summary["light_depth"].get<int>(), meta["depth"].get<int>() + 2);
    EXPECT_GE(summary["build_seconds"].get<double>(), 0.0);
    size_t wrong_route = 0, wrong_bytes = 0, inexact = 0;
    for (size_t i = 0; i < finest->grid.morton.size(); ++i) {
      const auto v = MortonDecode(finest->grid.morton[i]);
      char target[200];
      std::snprintf(target, sizeof(target), "%s/shadows/query?x=%.17g&y=%.17g&z=%.17g", autzen.c_str(),
                    origin[0] + (v[0] + 0.5) * voxel, origin[1] + (v[1] + 0.5) * voxel, origin[2] + (v[2] + 0.5) * voxel);
      const Response q = *c->Request("GET", target);
      ASSERT_EQ(q.status, 200) << target << " " << q.body;
      const nlohmann::json a = Json(q);
      wrong_route += a["shadowed"].get<bool>() != ((*exact)[i] != 0);
      inexact += !a["exact"].get<bool>() || a["voxel"] != nlohmann::json(v);
      wrong_bytes += served->Shadowed({v[0] + 0.5, v[1] + 0.5, v[2] + 0.5}) != ((*exact)[i] != 0);
    }
    EXPECT_EQ(wrong_route, 0u);
    EXPECT_EQ(wrong_bytes, 0u);
    EXPECT_EQ(inexact, 0u);
  };
  nlohmann::json job = Shade(*c, autzen, R"({"direction": [1, 0.5, -0.6], "bias": 1.5})");
  ASSERT_EQ(job["status"], "done") << job.dump();
  EXPECT_EQ(job["params"], nlohmann::json::parse(R"({"direction": [1, 0.5, -0.6], "bias": 1.5})"));
  expect_exact(1.5, "bias 1.5");
  const std::string first_etag = c->Request("GET", autzen + "/shadows/dag")->Header("etag");

  // A point of free space (the grid's top corner: the scan is flat) is answered but not exact; the
  // top face belongs to the last cell; the centre is in the dataset's frame.
  const uint32_t last = (1u << meta["depth"].get<int>()) - 1;
  const double top = meta["bounds"]["max"][2].get<double>();
  char air[200];
  std::snprintf(air, sizeof(air), "%s/shadows/query?x=%.17g&y=%.17g&z=%.17g", autzen.c_str(), meta["bounds"]["max"][0].get<double>(),
                meta["bounds"]["max"][1].get<double>(), top);
  r = *c->Request("GET", air);
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_FALSE(Json(r)["exact"].get<bool>());
  EXPECT_EQ(Json(r)["voxel"], nlohmann::json({last, last, last}));
  EXPECT_NEAR(Json(r)["centre"][2].get<double>(), top - voxel / 2, 1e-9);

  // Bad queries.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"", "give the point as ?x=&y=&z= in the dataset's frame; x is missing"},
      {"?x=1&y=2", "give the point as ?x=&y=&z= in the dataset's frame; z is missing"},
      {"?x=&y=2&z=3", "give the point as ?x=&y=&z= in the dataset's frame; x is missing"},
      {"?x=nan&y=0&z=0", "x=nan is not a finite number"},
      {"?x=0&y=inf&z=0", "y=inf is not a finite number"},
      {"?x=0&y=0&z=1e999", "z=1e999 is not a finite number"},
      {"?x=0&y=0&z=4x", "z=4x is not a finite number"},
      {"?x=-1e12&y=0&z=0", "the point is outside the dataset's grid: each coordinate from bounds.min to bounds.max (x from "},
  };
  for (const auto& [query, message] : bad) {
    r = *c->Request("GET", autzen + "/shadows/query" + query);
    EXPECT_EQ(r.status, 400) << query;
    EXPECT_EQ(ErrorOf(r).rfind(message, 0), 0u) << query << " -> " << ErrorOf(r);
  }
  r = *c->Request("POST", autzen + "/shadows/query?x=0&y=0&z=0", kAuth, "");
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(r.Header("allow"), "GET");

  // Replaced: the cached DAG goes with the set it came from.
  job = Shade(*c, autzen, R"({"direction": [1, 0.5, -0.6]})");
  ASSERT_EQ(job["status"], "done") << job.dump();
  EXPECT_NE(c->Request("GET", autzen + "/shadows/dag")->Header("etag"), first_etag);
  expect_exact(0, "replaced, bias 0");
  // Sun hours keep no DAG.
  job = Shade(*c, autzen, R"({"time": "2026-06-21T12:00:00-07:00", "until": "2026-06-21T18:00:00-07:00", "samples": 3})");
  ASSERT_EQ(job["status"], "done") << job.dump();
  EXPECT_TRUE(Json(*c->Request("GET", autzen + "/shadows"))["shadow_dag_bytes"].is_null());
  const std::string none = "the shadow set of dataset " + id + " has no shadow DAG (sun hours have none; POST a direction or a time for one)";
  for (const char* target : {"/shadows/dag", "/shadows/query?x=0&y=0&z=0"}) {
    r = *c->Request("GET", autzen + target);
    EXPECT_EQ(r.status, 404) << target;
    EXPECT_EQ(ErrorOf(r), none) << target;
  }
  const auto no_dag = client::FetchShadowDag(*c, autzen);
  EXPECT_FALSE(no_dag.ok());
  EXPECT_NE(no_dag.status().message().find("answered 404"), std::string::npos) << no_dag.status().ToString();
  // Deleted.
  ASSERT_EQ(Shade(*c, autzen, R"({"time": "2026-06-21T13:00:00-07:00"})")["status"], "done");
  EXPECT_EQ(c->Request("GET", air)->status, 200);
  EXPECT_EQ(c->Request("DELETE", autzen + "/shadows", kAuth)->status, 204);
  for (const char* target : {"/shadows/dag", "/shadows/query?x=0&y=0&z=0"}) {
    r = *c->Request("GET", autzen + target);
    EXPECT_EQ(r.status, 404) << target;
    EXPECT_EQ(ErrorOf(r), "dataset " + id + " has no shadows (POST /v1/datasets/" + id + "/shadows computes them)") << target;
  }
  const std::string metrics = c->Request("GET", "/metrics")->body;
  for (const char* label : {R"(route="/v1/datasets/{id}/shadows/query",status="200")", R"(route="/v1/datasets/{id}/shadows/dag",status="304")"}) {
    EXPECT_NE(metrics.find(label), std::string::npos) << label;
  }
}

// A store from before shadow DAGs were kept (no shadow_dags table): opened, migrated, its set
// served as before, with no DAG (404); a new job stores one, --check reads it and refuses junk.
TEST(ShadowDagStore, AnOlderStoreGetsTheTableAndCheckReadsTheDag) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir scratch;
  Daemon daemon(scratch.path());
  ASSERT_TRUE(daemon.Start());
  const std::string id = IngestAndShade(daemon, "tiny_1.2-with-color_1065pts.las", "name=old&voxel=2", R"({"direction": [0, 0, -1]})");
  ASSERT_FALSE(id.empty());
  daemon.Stop(SIGTERM);
  ASSERT_TRUE(testing::ExecSql(daemon.store(), "DROP TABLE shadow_dags"));
  ASSERT_TRUE(daemon.Start());
  auto c = daemon.Connect();
  EXPECT_EQ(c->Request("GET", "/v1/datasets/" + id + "/shadows")->status, 200);
  const Response r = *c->Request("GET", "/v1/datasets/" + id + "/shadows/dag");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(ErrorOf(r), "the shadow set of dataset " + id + " has no shadow DAG (sun hours have none; POST a direction or a time for one)");
  // A new job stores one again.
  const Response posted = Post(*c, "/v1/datasets/" + id + "/shadows", R"({"direction": [0, 0, -1]})");
  ASSERT_EQ(WaitForJob(*c, posted.Header("location"))["status"], "done");
  EXPECT_EQ(c->Request("GET", "/v1/datasets/" + id + "/shadows/dag")->status, 200);
  daemon.Stop(SIGTERM);
  EXPECT_EQ(RunCheck(daemon.var()).first, 0) << RunCheck(daemon.var()).second;
  // A shadow DAG whose checksum holds but whose bytes are not a shadow DAG.
  const std::vector<uint8_t> junk = {'P', 'D', 'S', 'D', 9, 0, 0, 0};
  ASSERT_TRUE(testing::ExecSql(daemon.store(), "UPDATE shadow_dags SET bytes = X'5044534409000000', etag = '" +
                                                   server::TileEtag(junk) + "'"));
  const auto [code, out] = RunCheck(daemon.var());
  EXPECT_EQ(code, 1);
  EXPECT_NE(out.find("the shadow DAG of dataset " + id + ": "), std::string::npos) << out;
}

}  // namespace
}  // namespace pointdag
