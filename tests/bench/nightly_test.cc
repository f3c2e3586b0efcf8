// The nightly benchmark (bench/, `pointdag bench --corpus`): corpus files, the report against
// `pointdag compare`, the baseline check through the real CLI.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "pointdag/bench/corpus.h"
#include "pointdag/bench/corpus_case.h"
#include "pointdag/bench/report.h"
#include "pointdag/ingest.h"
#include "pointdag/read/scan_reader.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::Cli;
using testing::DataDir;
using testing::ScratchDir;

void WriteText(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

const nlohmann::json& Row(const nlohmann::json& rows, const std::string& key) {
  for (const auto& row : rows) {
    if (CodecRowKey(row) == key) return row;
  }
  ADD_FAILURE() << "no row " << key << " in " << rows.dump();
  static const nlohmann::json none;
  return none;
}

TEST(Corpus, TomlCasesWithVoxelsTargetsAndDerivedSizes) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto tiny = DataDir() / "tiny_1.2-with-color_1065pts.las";
  WriteText(dir / "corpus.toml", "targets = [36.0, 40.0]\n"
                                 "[[scan]]\nfile = \"" + tiny.string() + "\"\nvoxel = 8.0\n"
                                 "[[scan]]\nfile = \"" + tiny.string() + "\"\ntargets = [38.0]\n");
  auto cases = LoadCorpus(dir / "corpus.toml");
  ASSERT_TRUE(cases.ok()) << cases.status().ToString();
  ASSERT_EQ(cases->size(), 2u);
  EXPECT_EQ((*cases)[0].voxel, 8.0);
  EXPECT_FALSE((*cases)[0].voxel_derived);
  EXPECT_EQ((*cases)[0].targets, (std::vector<double>{36.0, 40.0}));
  auto reader = OpenScan(tiny);
  ASSERT_TRUE(reader.ok());
  auto derived = DeriveVoxelSize(**reader);  // what pointdagd gives an upload without a voxel size
  ASSERT_TRUE(derived.ok());
  EXPECT_EQ((*cases)[1].voxel, *derived);
  EXPECT_TRUE((*cases)[1].voxel_derived);
  EXPECT_EQ((*cases)[1].targets, (std::vector<double>{38.0}));
}

TEST(Corpus, TheShippedCorpusNamesTheSharedScans) {
  SKIP_WITHOUT_DATA();
  auto cases = LoadCorpus(std::filesystem::path(POINTDAG_SOURCE_DIR) / "configs" / "corpus.toml");
  ASSERT_TRUE(cases.ok()) << cases.status().ToString();
  EXPECT_EQ(cases->size(), 6u);
  for (const auto& c : *cases) EXPECT_FALSE(c.voxel_derived) << c.scan;
}

TEST(Corpus, AFolderIsEveryScanInItAtItsDerivedSize) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  std::filesystem::copy_file(DataDir() / "tiny_1.2-with-color_1065pts.las", dir / "tiny.las");
  WriteText(dir / "README.md", "not a scan\n");
  auto cases = LoadCorpus(dir.path());
  ASSERT_TRUE(cases.ok()) << cases.status().ToString();
  ASSERT_EQ(cases->size(), 1u);
  EXPECT_EQ((*cases)[0].scan.filename(), "tiny.las");
  EXPECT_TRUE((*cases)[0].voxel_derived);
  EXPECT_EQ((*cases)[0].targets, kDefaultCorpusTargets);
}

TEST(Corpus, BadCorporaAreTypedErrorsNamingWhere) {
  ScratchDir dir;
  EXPECT_EQ(LoadCorpus(dir / "missing.toml").status().code(), StatusCode::kIoError);
  EXPECT_EQ(LoadCorpus(dir.path()).status().code(), StatusCode::kInvalidArgument);  // a folder without scans
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"targets = [38.0\n", "corpus.toml:"},
      {"title = 1\n", "no [[scan]]"},
      {"[[scan]]\nvoxel = 1.0\n", "scan 1: file is missing"},
      {"[[scan]]\nfile = \"nowhere.las\"\n", "does not exist"},
      {"[[scan]]\nfile = \"corpus.toml\"\nvoxel = -1.0\n", "scan 1: voxel must be a positive number"},
      {"[[scan]]\nfile = \"corpus.toml\"\nvoxel = 1.0\ntargets = [300.0]\n", "outside 10..99"},
      {"[[scan]]\nfile = \"corpus.toml\"\nvoxel = 1.0\ntargets = [\"high\"]\n", "list of numbers"},
  };
  for (const auto& [text, message] : bad) {
    WriteText(dir / "corpus.toml", text);
    const Status s = LoadCorpus(dir / "corpus.toml").status();
    EXPECT_FALSE(s.ok()) << text;
    EXPECT_NE(s.message().find(message), std::string::npos) << text << " -> " << s.ToString();
  }
}

// The report's values are `pointdag compare`'s for the same scan and voxel size.
TEST(Nightly, CaseEqualsWhatCompareReports) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto scan = DataDir() / "autzen_trim_pdrf3_rgb.las";
  const nlohmann::json c = RunCorpusCase({scan, 4.0, false, {34.0, 38.0}});
  ASSERT_FALSE(c.contains("error")) << c.dump();
  const auto compare = Cli("compare " + scan.string() + " --voxel 4 --json", dir, "POINTDAG_DEVICE=cpu");
  ASSERT_EQ(compare.exit_code, 0) << compare.err;
  const auto card = nlohmann::json::parse(compare.out);
  EXPECT_EQ(c["voxels"], card["voxels"]);
  EXPECT_EQ(c["points"], card["points"]);
  EXPECT_EQ(c["geometry_bits_per_voxel"], card["geometry_bits_per_voxel"]);
  EXPECT_EQ(c["draco_bits_per_point"], card["draco_bits_per_point"]);
  EXPECT_EQ(c["original"]["d1_mse"], card["original"]["d1_mse"]);
  for (const auto& codec : card["codecs"]) {
    const std::string name = codec["name"];
    if (name != "vbr" && name != "fixed3" && name != "lossless") continue;
    if (codec["target_psnr"].is_number() && codec["target_psnr"] != 34.0 && codec["target_psnr"] != 38.0) continue;
    const nlohmann::json& row = Row(c["ours"], CodecRowKey({{"codec", name}, {"target_psnr", codec["target_psnr"]}}));
    EXPECT_EQ(row["bits_per_point"], codec["total_bits_per_voxel"]) << name;
    EXPECT_EQ(row["psnr_y"], codec["psnr_y"]) << name;
    EXPECT_EQ(row["psnr_y_vs_original"], codec["psnr_y_vs_original"]) << name;
  }
  // The best image mapping at 38 dB is the smallest of compare's image rows there.
  double smallest = INFINITY;
  for (const auto& codec : card["codecs"]) {
    if (!codec["curve"].is_null() && codec["target_psnr"] == 38.0) smallest = std::min(smallest, codec["total_bits_per_voxel"].get<double>());
  }
  EXPECT_EQ(Row(c["ours"], "image@38")["bits_per_point"].get<double>(), smallest);
  EXPECT_GT(c["speed"]["ours_decode_points_per_second"].get<double>(), 0);
  EXPECT_GT(c["speed"]["draco_decode_points_per_second"].get<double>(), 0);
  EXPECT_GT(c["peak_rss_bytes"].get<double>(), 0);
}

TEST(Nightly, CommandWritesReportsAndFailsOnARegression) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  WriteText(dir / "corpus.toml", "targets = [38.0]\n[[scan]]\nfile = \"" + (DataDir() / "tiny_1.2-with-color_1065pts.las").string() +
                                     "\"\nvoxel = 8.0\n");
  const std::string corpus = " --corpus " + (dir / "corpus.toml").string() + " --out " + (dir / "reports").string();
  const auto first = Cli("bench" + corpus, dir, "POINTDAG_DEVICE=cpu");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  auto reports = ListReports(dir / "reports");
  ASSERT_EQ(reports.size(), 1u);
  const nlohmann::json report = ReadJson(reports[0]);
  EXPECT_EQ(report["schema"], 1);
  EXPECT_FALSE(report["machine"]["cpu"].get<std::string>().empty());
  EXPECT_EQ(report["versions"]["draco"], DracoVersion());
  EXPECT_EQ(report["versions"]["pointdag"], PointdagVersion());
  ASSERT_EQ(report["cases"].size(), 1u);
  EXPECT_EQ(report["cases"][0]["scan"], "tiny_1.2-with-color_1065pts.las");
  EXPECT_EQ(report["cases"][0]["voxels"], 1063);
  const auto html_bytes = testing::ReadBytes(std::filesystem::path(reports[0]).replace_extension(".html"));
  const std::string html(html_bytes.begin(), html_bytes.end());
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);

  // Same code, same corpus: the newest report is the baseline and nothing regressed.
  const auto second = Cli("bench" + corpus + " --keep 1", dir, "POINTDAG_DEVICE=cpu");
  EXPECT_EQ(second.exit_code, 0) << second.err;
  EXPECT_EQ(ListReports(dir / "reports").size(), 1u);  // --keep 1

  // A baseline whose VBR at 38 dB was 10% smaller: the run fails, naming the case and the row.
  nlohmann::json smaller = ReadJson(ListReports(dir / "reports")[0]);
  for (auto& row : smaller["cases"][0]["ours"]) {
    if (CodecRowKey(row) == "vbr@38") row["bits_per_point"] = row["bits_per_point"].get<double>() * 0.9;
  }
  WriteText(dir / "baseline.json", smaller.dump());
  const auto third = Cli("bench" + corpus + " --baseline " + (dir / "baseline.json").string(), dir, "POINTDAG_DEVICE=cpu");
  EXPECT_EQ(third.exit_code, 3) << third.err;
  EXPECT_NE(third.err.find("tiny_1.2-with-color_1065pts.las at voxel 8: vbr@38 grew"), std::string::npos) << third.err;
  EXPECT_NE(third.err.find("pointdag " + PointdagVersion()), std::string::npos) << third.err;

  // A baseline that is not a report is an error, not a crash.
  WriteText(dir / "baseline.json", R"({"cases": [{"scan": 3}]})");
  const auto fourth = Cli("bench" + corpus + " --baseline " + (dir / "baseline.json").string(), dir, "POINTDAG_DEVICE=cpu");
  EXPECT_EQ(fourth.exit_code, 1);
  EXPECT_NE(fourth.err.find("is not a pointdag benchmark report"), std::string::npos) << fourth.err;
}

}  // namespace
}  // namespace pointdag
