// `pointdag shadow` (issue #16) as a user runs it: the real binary on real scans at low resolution,
// its numbers checked against the library's exact per-voxel shadows.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <numeric>

#include "pointdag/container/pdag_file.h"
#include "pointdag/pipeline.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/shadow/shadow_dag.h"
#include "pointdag/shadow/solar_position.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::Cli;
using testing::CliRun;
using testing::DataDir;
using testing::ScratchDir;

// Autzen has a CRS (Oregon, lat 44.05, lon -123.07): 08:00 UTC is 1 am there, 20:00 UTC 1 pm.
constexpr const char* kGeoScan = "autzen_trim_pdrf3_rgb.las";
constexpr const char* kLocalScan = "tiny_1.2-with-color_1065pts.las";  // no CRS

std::string Scan(const char* name) { return (DataDir() / name).string(); }

nlohmann::json RunJson(const std::string& args, const ScratchDir& dir) {
  const CliRun run = Cli("shadow " + args + " --json", dir);
  EXPECT_EQ(run.exit_code, 0) << args << "\n" << run.err;
  return run.exit_code == 0 ? nlohmann::json::parse(run.out) : nlohmann::json::object();
}

// The scan as the command voxelizes it: encode --georeference.
Svdag VoxelizeLikeTheCli(const char* name, int depth) {
  EncodeOptions options;
  options.depth = depth;
  options.georeference = true;
  options.colors = {ColorCodec::kRaw, std::nullopt};
  auto encoded = EncodeScan(DataDir() / name, options);
  EXPECT_TRUE(encoded.ok()) << encoded.status().ToString();
  return encoded.ok() ? std::move(encoded->dag) : Svdag{};
}

uint64_t Sum(const std::vector<uint8_t>& bits) { return std::accumulate(bits.begin(), bits.end(), uint64_t{0}); }

TEST(ShadowCli, DirectionCountsMatchTheExactShadows) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  for (const char* name : {kGeoScan, kLocalScan}) {
    const nlohmann::json r = RunJson(Scan(name) + " --depth 7 --direction 1,0.5,-1", dir);
    const Svdag dag = VoxelizeLikeTheCli(name, 7);
    auto light = LightFromDirection(1, 0.5, -1);
    ASSERT_TRUE(light.ok());
    auto shadowed = ShadowedVoxels(dag, *light);
    ASSERT_TRUE(shadowed.ok()) << shadowed.status().ToString();
    EXPECT_EQ(r["surface_voxels"].get<uint64_t>(), shadowed->size()) << name;
    EXPECT_EQ(r["shadowed_voxels"].get<uint64_t>(), Sum(*shadowed)) << name;
    EXPECT_GT(r["shadowed_voxels"].get<uint64_t>(), 0u) << name;
    EXPECT_LT(r["shadowed_voxels"].get<uint64_t>(), r["surface_voxels"].get<uint64_t>()) << name;
    EXPECT_GT(r["shadow_dag_bytes"].get<uint64_t>(), 0u);
    EXPECT_GT(r["dense_grid_bytes"].get<uint64_t>(), 0u);
    EXPECT_GT(r["shadow_map_bytes"].get<uint64_t>(), 0u);
    EXPECT_EQ(r["light_depth"].get<int>(), 9);
    EXPECT_GE(r["build_seconds"].get<double>(), 0.0);
    EXPECT_FALSE(r["below_horizon"].get<bool>());
    EXPECT_EQ(r["samples"].get<int>(), 1);
    EXPECT_TRUE(r["light"]["sun"].is_null());
    EXPECT_NEAR(r["light"]["direction"][0].get<double>(), 1 / 1.5, 1e-12);  // normalized: |(1, .5, -1)| = 1.5
  }
  const CliRun text = Cli("shadow " + Scan(kLocalScan) + " --depth 6 --direction 0,0,-1", dir);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("shadow DAG"), std::string::npos) << text.out;
}

TEST(ShadowCli, SunAtNightShadowsEverythingAndByDayNot) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const nlohmann::json night = RunJson(Scan(kGeoScan) + " --depth 6 --time 2026-06-21T08:00:00Z", dir);
  EXPECT_TRUE(night["below_horizon"].get<bool>());
  EXPECT_EQ(night["shadowed_voxels"], night["surface_voxels"]);
  EXPECT_LT(night["light"]["sun"]["elevation_deg"].get<double>(), 0.0);
  EXPECT_NEAR(night["light"]["sun"]["latitude_deg"].get<double>(), 44.05, 0.05);
  EXPECT_NEAR(night["light"]["sun"]["longitude_deg"].get<double>(), -123.07, 0.05);

  const nlohmann::json day = RunJson(Scan(kGeoScan) + " --depth 6 --time 2026-06-21T13:00:00-07:00", dir);
  EXPECT_FALSE(day["below_horizon"].get<bool>());
  const auto& sun = day["light"]["sun"];
  auto expected = SolarPosition(*ParseUtcTime("2026-06-21T20:00:00Z"), sun["latitude_deg"], sun["longitude_deg"]);
  ASSERT_TRUE(expected.ok());
  EXPECT_NEAR(sun["elevation_deg"].get<double>(), expected->elevation_deg, 1e-9);
  EXPECT_NEAR(sun["azimuth_deg"].get<double>(), expected->azimuth_deg, 1e-9);
  EXPECT_GT(sun["elevation_deg"].get<double>(), 60.0);  // early afternoon at midsummer, lat 44
  EXPECT_LT(day["shadowed_voxels"].get<uint64_t>(), day["surface_voxels"].get<uint64_t>());
  EXPECT_LT(day["light"]["direction"][2].get<double>(), 0.0);  // travelling down
}

TEST(ShadowCli, TimeNeedsAGeoreferencedDataset) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const CliRun run = Cli("shadow " + Scan(kLocalScan) + " --depth 6 --time 2026-06-21T12:00:00Z", dir);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("georeferenced"), std::string::npos) << run.err;
  EXPECT_TRUE(run.out.empty()) << run.out;
}

TEST(ShadowCli, BadLightsAreBadInputAndBadCombinationsUsage) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const std::string scan = Scan(kLocalScan) + " --depth 6";
  for (const char* direction : {"0,0,0", "nan,0,-1", "1,inf,-1", "up", "1,2", "1,2,3,4", "1,,2", "1,2,3x", "-1,0,0,"}) {
    const CliRun run = Cli("shadow " + scan + " --direction '" + direction + "'", dir);
    EXPECT_EQ(run.exit_code, 1) << direction << ": " << run.err;
    EXPECT_NE(run.err.find("InvalidArgument"), std::string::npos) << direction << ": " << run.err;
  }
  for (const char* time : {"2026-06-21T12:00:00", "yesterday", "2026-02-30T12:00:00Z"}) {
    EXPECT_EQ(Cli("shadow " + Scan(kGeoScan) + " --depth 6 --time " + time, dir).exit_code, 1) << time;
  }
  const std::string at = " --time 2026-06-21T12:00:00Z";
  EXPECT_EQ(Cli("shadow " + Scan(kGeoScan) + " --depth 6" + at + " --until 2026-06-21T20:00:00Z --samples 0", dir).exit_code, 2);
  EXPECT_EQ(Cli("shadow " + Scan(kGeoScan) + " --depth 6" + at + " --until 2026-06-21T10:00:00Z --samples 3", dir).exit_code, 1);
  for (const std::string& args :
       {scan + at + " --samples 4", scan + at + " --until 2026-06-21T20:00:00Z", scan, scan + at + " --direction 0,0,-1",
        Scan(kLocalScan) + " --direction 0,0,-1", scan + " --direction 0,0,-1 --voxel 1",
        scan + " --direction 0,0,-1 -o x.txt", scan + " --direction 0,0,-1 --samples 3"}) {
    const CliRun run = Cli("shadow " + args, dir);
    EXPECT_EQ(run.exit_code, 2) << args << ": " << run.err;
  }
}

TEST(ShadowCli, SunHoursAgreeWithLitSampleCountsAndWritePly) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const std::string ply = (dir / "hours.ply").string();
  // 05:00 to 21:00 local (PDT) on midsummer day, 9 samples two hours apart.
  const nlohmann::json r = RunJson(Scan(kGeoScan) + " --depth 6 --time 2026-06-21T05:00:00-07:00 --until "
                                   "2026-06-21T21:00:00-07:00 --samples 9 -o " + ply, dir);
  ASSERT_FALSE(r["sun_hours"].is_null());
  const auto& h = r["sun_hours"];
  EXPECT_EQ(r["samples"].get<int>(), 9);
  EXPECT_DOUBLE_EQ(h["span_hours"].get<double>(), 16.0);
  const auto histogram = h["lit_count_histogram"].get<std::vector<uint64_t>>();
  ASSERT_EQ(histogram.size(), 10u);
  EXPECT_EQ(std::accumulate(histogram.begin(), histogram.end(), uint64_t{0}), r["surface_voxels"].get<uint64_t>());

  const auto& sun = r["light"]["sun"];
  auto lights = SunLights(*ParseUtcTime("2026-06-21T12:00:00Z"), *ParseUtcTime("2026-06-22T04:00:00Z"), 9,
                          sun["latitude_deg"], sun["longitude_deg"]);
  ASSERT_TRUE(lights.ok());
  auto lit = LitSampleCounts(VoxelizeLikeTheCli(kGeoScan, 6), *lights);
  ASSERT_TRUE(lit.ok()) << lit.status().ToString();
  const double mean = std::accumulate(lit->begin(), lit->end(), 0.0) / static_cast<double>(lit->size());
  EXPECT_NEAR(h["mean_hours"].get<double>(), mean * 16.0 / 9.0, 1e-9);
  EXPECT_GT(h["max_hours"].get<double>(), h["min_hours"].get<double>());
  EXPECT_EQ(histogram[0], static_cast<uint64_t>(std::count(lit->begin(), lit->end(), 0)));

  auto reader = OpenScan(ply);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().point_count, r["surface_voxels"].get<uint64_t>());
  const auto bytes = testing::ReadBytes(ply);
  const std::string head(bytes.begin(), bytes.begin() + 400);
  EXPECT_NE(head.find("property float sun_hours"), std::string::npos) << head;
}

TEST(ShadowCli, PdagInputAndShadowDagOutput) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const std::string pdag = (dir / "a.pdag").string();
  const CliRun encode = Cli("encode " + Scan(kGeoScan) + " --georeference --depth 6 -o " + pdag, dir);
  ASSERT_EQ(encode.exit_code, 0) << encode.err;
  const std::string pdsh = (dir / "a.pdsh").string();
  const nlohmann::json from_pdag = RunJson(pdag + " --time 2026-06-21T13:00:00-07:00 -o " + pdsh, dir);
  const nlohmann::json from_scan = RunJson(Scan(kGeoScan) + " --depth 6 --time 2026-06-21T13:00:00-07:00", dir);
  EXPECT_EQ(from_pdag["surface_voxels"], from_scan["surface_voxels"]);
  EXPECT_EQ(from_pdag["shadowed_voxels"], from_scan["shadowed_voxels"]);
  EXPECT_EQ(from_pdag["light"]["direction"], from_scan["light"]["direction"]);

  auto bytes = ReadFileBytes(pdsh);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  auto shadow = ShadowDag::Deserialize(*bytes);
  ASSERT_TRUE(shadow.ok()) << shadow.status().ToString();
  EXPECT_EQ(shadow->stats().light_depth, from_pdag["light_depth"].get<int>());
  // Without --georeference a .pdag keeps the scan's own axes: no sun for it.
  const std::string plain = (dir / "plain.pdag").string();
  ASSERT_EQ(Cli("encode " + Scan(kGeoScan) + " --depth 6 -o " + plain, dir).exit_code, 0);
  const CliRun no_sun = Cli("shadow " + plain + " --time 2026-06-21T13:00:00-07:00", dir);
  EXPECT_EQ(no_sun.exit_code, 1);
  EXPECT_NE(no_sun.err.find("georeferenced"), std::string::npos) << no_sun.err;
  EXPECT_EQ(Cli("shadow " + plain + " --direction 0,0,-1", dir).exit_code, 0);
  // A .pdag has its own grid; and sun hours do not fit a one-light .pdsh.
  EXPECT_EQ(Cli("shadow " + pdag + " --depth 6 --direction 0,0,-1", dir).exit_code, 2);
  EXPECT_EQ(Cli("shadow " + pdag + " --time 2026-06-21T12:00:00Z --until 2026-06-21T20:00:00Z --samples 3 -o x.pdsh", dir)
                .exit_code, 2);
}

// `bench --shadow DIR` reaches RunShadowBench (shadow_bench.h): a table row per scan and resolution.
TEST(ShadowCli, BenchShadowRunsOnAFolder) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  std::filesystem::create_directories(dir / "scans");
  std::filesystem::copy_file(DataDir() / kLocalScan, dir / "scans" / kLocalScan);
  const CliRun run = Cli("bench --shadow " + (dir / "scans").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  size_t rows = 0;
  for (size_t at = run.out.find(std::string("| ") + kLocalScan); at != std::string::npos;
       at = run.out.find(std::string("| ") + kLocalScan, at + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, 2u) << run.out;
  // The exact shadows' table names the benchmark scans the folder lacks.
  EXPECT_NE(run.out.find("not in " + (dir / "scans").string() + ": lion_takanawa_pdrf7_rgb.las"), std::string::npos)
      << run.out;
  std::filesystem::create_directories(dir / "empty");
  EXPECT_EQ(Cli("bench --shadow " + (dir / "empty").string(), dir).exit_code, 1);
}

// --bias VOXELS reaches every light (one direction, and each sun of sun hours), is echoed, and is
// checked before the load; without it the answers are the definition (bias 0).
TEST(ShadowCli, BiasReachesTheLightsAndIsChecked) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const Svdag dag = VoxelizeLikeTheCli(kGeoScan, 7);
  auto light = LightFromDirection(1, 0.5, -0.6);  // about 28 degrees high: flat ground shadows itself
  ASSERT_TRUE(light.ok());
  std::vector<uint64_t> counts;
  for (double bias : {0.0, 1.5, 3.0}) {  // ground lit from 0.5 / sin 28.2 = 1.06 on
    const std::string flag = bias == 0 ? "" : " --bias " + std::to_string(bias);
    const nlohmann::json r = RunJson(Scan(kGeoScan) + " --depth 7 --direction 1,0.5,-0.6" + flag, dir);
    Light biased = *light;
    biased.bias_voxels = bias;
    auto shadowed = ShadowedVoxels(dag, biased);
    ASSERT_TRUE(shadowed.ok()) << shadowed.status().ToString();
    EXPECT_EQ(r["bias"].get<double>(), bias);
    EXPECT_EQ(r["shadowed_voxels"].get<uint64_t>(), Sum(*shadowed)) << bias;
    counts.push_back(r["shadowed_voxels"].get<uint64_t>());
  }
  EXPECT_GT(counts[0], counts[1]);
  EXPECT_GE(counts[1], counts[2]);
  // Sun hours: every sample carries the bias.
  const std::string span = " --time 2026-06-21T05:00:00-07:00 --until 2026-06-21T21:00:00-07:00 --samples 5";
  const nlohmann::json hours = RunJson(Scan(kGeoScan) + " --depth 7 --bias 2" + span, dir);
  const auto& sun = hours["light"]["sun"];
  auto lights = SunLights(*ParseUtcTime("2026-06-21T12:00:00Z"), *ParseUtcTime("2026-06-22T04:00:00Z"), 5,
                          sun["latitude_deg"], sun["longitude_deg"]);
  ASSERT_TRUE(lights.ok());
  for (Light& l : *lights) l.bias_voxels = 2;
  auto lit = LitSampleCounts(dag, *lights);
  ASSERT_TRUE(lit.ok()) << lit.status().ToString();
  EXPECT_EQ(hours["sun_hours"]["never_lit"].get<uint64_t>(), static_cast<uint64_t>(std::count(lit->begin(), lit->end(), 0)));
  EXPECT_NEAR(hours["sun_hours"]["mean_hours"].get<double>(),
              std::accumulate(lit->begin(), lit->end(), 0.0) / static_cast<double>(lit->size()) * 16.0 / 5.0, 1e-9);
  // Out of range or not a number: bad input, named, before the scan is read.
  for (const char* bias : {"-1", "16.5", "nan", "inf"}) {
    const CliRun run = Cli("shadow " + Scan(kGeoScan) + " --depth 7 --direction 0,0,-1 --bias " + bias, dir);
    EXPECT_EQ(run.exit_code, 1) << bias << ": " << run.err;
    EXPECT_NE(run.err.find("--bias"), std::string::npos) << bias << ": " << run.err;
  }
  EXPECT_EQ(Cli("shadow " + Scan(kGeoScan) + " --depth 7 --direction 0,0,-1 --bias one", dir).exit_code, 2);
}

}  // namespace
}  // namespace pointdag
