#include <gtest/gtest.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>
#include <map>
#include <set>

#include "hostile_pdag.h"
#include "pointdag/read/scan_reader.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::DataDir;
using testing::Cli;
using testing::CliRun;
using testing::ScratchDir;

TEST(Cli, EncodeInfoDecodeRoundTrip) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto scan = (DataDir() / "autzen_trim_pdrf3_rgb.las").string();
  const auto pdag = (dir / "a.pdag").string();
  const CliRun encode = Cli("encode " + scan + " -o " + pdag + " --voxel 4", dir);
  ASSERT_EQ(encode.exit_code, 0) << encode.err;
  EXPECT_NE(encode.err.find("36931 voxels"), std::string::npos) << encode.err;

  const CliRun info = Cli("info " + pdag + " --json", dir);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto json = nlohmann::json::parse(info.out);
  EXPECT_EQ(json["voxels"], 36931);
  EXPECT_EQ(json["depth"], 9);
  EXPECT_GT(json["sections"]["geometry"].get<int>(), 0);
  EXPECT_GT(json["sections"]["colors"].get<int>(), 0);
  EXPECT_EQ(json["meta"]["codec"]["colors"]["codec"], "lossless");  // nothing is degraded unless asked
  EXPECT_EQ(json["file_bytes"], std::filesystem::file_size(pdag));

  const CliRun text_info = Cli("info " + pdag, dir);
  EXPECT_EQ(text_info.exit_code, 0);
  EXPECT_NE(text_info.out.find("Lambert_Conformal_Conic"), std::string::npos) << text_info.out;

  const auto ply = (dir / "a.ply").string();
  const CliRun decode = Cli("decode " + pdag + " -o " + ply, dir);
  ASSERT_EQ(decode.exit_code, 0) << decode.err;
  // The decoded PLY is a scan in its own right: one point per voxel, with color.
  auto reader = OpenScan(ply);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().point_count, 36931u);
  EXPECT_TRUE((*reader)->info().has_color);
}

TEST(Cli, CompareReportsUsAndDracoOnTheSameVoxels) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const CliRun run = Cli("compare " + (DataDir() / "tiny_1.2-with-color_1065pts.las").string() + " --depth 8 --json", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["depth"], 8);
  EXPECT_GT(json["voxels"].get<int>(), 0);
  EXPECT_GT(json["geometry_bits_per_voxel"].get<double>(), 0.0);
  EXPECT_GT(json["draco_bits_per_point"].get<double>(), 0.0);
  EXPECT_GT(json["original"]["d1_mse"].get<double>(), 0.0);
  EXPECT_GT(json["original"]["d1_psnr"].get<double>(), 0.0);
  std::set<std::pair<std::string, int>> seen;
  for (const auto& codec : json["codecs"]) {
    const std::string name = codec["name"];
    if (codec["target_psnr"].is_null()) {
      EXPECT_TRUE(codec["lossless"].get<bool>()) << name;
      if (name == "raw") {
        EXPECT_NEAR(codec["color_bits_per_voxel"].get<double>(), 24.0, 0.01);  // plus the codec's id byte
      }
      seen.insert({name, 0});
    } else {
      EXPECT_GE(codec["psnr_y"].get<double>(), codec["target_psnr"].get<double>()) << name;
      seen.insert({name, codec["target_psnr"].get<int>()});
    }
    EXPECT_GT(codec["color_bits_per_voxel"].get<double>(), 0.0);
  }
  for (const char* name : {"vbr", "fixed3", "hierarchical", "jpeg", "webp"}) {
    for (int target : {30, 34, 38, 42}) EXPECT_EQ(seen.count({name, target}), 1u) << name << " " << target;
  }
  EXPECT_EQ(seen.count({"lossless", 0}), 1u);
  EXPECT_EQ(seen.count({"png", 0}), 1u);
}

TEST(Cli, QualityFlagStoresLossyColorsThatMeetTheTarget) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto pdag = (dir / "q.pdag").string();
  const CliRun encode = Cli("encode " + (DataDir() / "autzen_trim_pdrf3_rgb.las").string() + " -o " + pdag +
                                " --voxel 4 --quality 34",
                            dir);
  ASSERT_EQ(encode.exit_code, 0) << encode.err;
  EXPECT_NE(encode.err.find("colors (vbr)"), std::string::npos) << encode.err;
  const auto info = nlohmann::json::parse(Cli("info " + pdag + " --json", dir).out);
  EXPECT_EQ(info["meta"]["codec"]["colors"]["codec"], "vbr");
  EXPECT_GE(info["meta"]["codec"]["colors"]["psnr_y"].get<double>(), 34.0);
  EXPECT_LT(info["sections"]["colors"].get<int>(), 36931);  // under a byte per voxel
  EXPECT_EQ(Cli("decode " + pdag + " -o " + (dir / "q.ply").string(), dir).exit_code, 0);
  // A lossless codec with a quality target is a usage error.
  EXPECT_EQ(Cli("encode " + (DataDir() / "tiny_1.2-with-color_1065pts.las").string() + " -o x.pdag --depth 6 "
                "--quality 30 --color-codec lossless", dir).exit_code, 2);
  EXPECT_EQ(Cli("encode " + (DataDir() / "tiny_1.2-with-color_1065pts.las").string() + " -o x.pdag --depth 6 "
                "--quality 30 --lossless", dir).exit_code, 2);
}

// The hierarchical colors from the CLI: the same target in fewer bytes than VBR's, a file that
// decodes, in mipmap mode too (which stores the voxels' colors only: the same section, flagged).
TEST(Cli, HierarchicalColorsMeetTheTargetInFewerBytesThanVbr) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto scan = (DataDir() / "autzen_trim_pdrf3_rgb.las").string();
  std::map<std::string, nlohmann::json> info;
  for (const std::string codec : {"vbr", "hierarchical"}) {
    const auto pdag = (dir / (codec + ".pdag")).string();
    const CliRun encode = Cli("encode " + scan + " -o " + pdag + " --voxel 4 --quality 34 --color-codec " + codec, dir);
    ASSERT_EQ(encode.exit_code, 0) << encode.err;
    info[codec] = nlohmann::json::parse(Cli("info " + pdag + " --json", dir).out);
    EXPECT_EQ(info[codec]["meta"]["codec"]["colors"]["codec"], codec);
    EXPECT_GE(info[codec]["meta"]["codec"]["colors"]["psnr_y"].get<double>(), 34.0) << codec;
    EXPECT_EQ(Cli("decode " + pdag + " -o " + (dir / (codec + ".ply")).string(), dir).exit_code, 0) << codec;
  }
  EXPECT_LT(info["hierarchical"]["sections"]["colors"].get<int>(), info["vbr"]["sections"]["colors"].get<int>() * 3 / 4);
  const CliRun mipmap = Cli("encode " + scan + " -o " + (dir / "m.pdag").string() +
                                " --voxel 4 --quality 34 --color-codec hierarchical --mipmap",
                            dir);
  ASSERT_EQ(mipmap.exit_code, 0) << mipmap.err;
  const auto mip_info = nlohmann::json::parse(Cli("info " + (dir / "m.pdag").string() + " --json", dir).out);
  EXPECT_EQ(mip_info["meta"]["codec"]["count_mode"], "mipmap");
  EXPECT_EQ(mip_info["sections"]["colors"], info["hierarchical"]["sections"]["colors"]);
  EXPECT_EQ(Cli("decode " + (dir / "m.pdag").string() + " -o " + (dir / "m.ply").string(), dir).exit_code, 0);
}

TEST(Cli, ExitCodesAreOneForBadInputAndTwoForUsage) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  auto bytes = testing::ReadBytes(DataDir() / "tiny_1.2-with-color_1065pts.las");
  bytes.resize(bytes.size() - 100);
  testing::WriteBytes(dir / "cut.las", bytes);
  const CliRun bad = Cli("encode " + (dir / "cut.las").string() + " -o " + (dir / "out.pdag").string() + " --depth 8", dir);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("Truncated"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.pdag"));  // nothing half-written

  testing::WriteBytes(dir / "junk.pdag", {1, 2, 3});
  EXPECT_EQ(Cli("info " + (dir / "junk.pdag").string(), dir).exit_code, 1);
  EXPECT_EQ(Cli("decode " + (dir / "missing.pdag").string() + " -o x.ply", dir).exit_code, 1);

  const std::string scan = (DataDir() / "tiny_1.2-with-color_1065pts.las").string();
  EXPECT_EQ(Cli("", dir).exit_code, 2);
  EXPECT_EQ(Cli("frobnicate", dir).exit_code, 2);
  EXPECT_EQ(Cli("encode " + scan + " -o x.pdag", dir).exit_code, 2);  // neither --voxel nor --depth
  EXPECT_EQ(Cli("encode " + scan + " -o x.pdag --voxel 1 --depth 5", dir).exit_code, 2);
  EXPECT_EQ(Cli("encode " + scan + " -o x.pdag --depth 30", dir).exit_code, 2);
  EXPECT_EQ(Cli("encode " + scan + " -o x.pdag --voxel -1", dir).exit_code, 2);
  EXPECT_EQ(Cli("--help", dir).exit_code, 0);
}

// Issue 11: hostile .pdag files made `info` and `decode` die of bad_alloc, an uncaught type_error
// or a stack overflow. Each is now exit 1 and `pointdag: <reason>`.
TEST(Cli, HostilePdagIsExitOneWithAReasonNeverAnAbort) {
  ScratchDir dir;
  const auto geometry = EncodeDag(testing::DenseCube(4), GeometryCoder::kContext).value();
  const auto write = [&](const std::string& name, nlohmann::json meta, const std::vector<uint8_t>& geo) {
    PdagFile file;
    file.meta = std::move(meta);
    file.geometry = geo;
    ASSERT_TRUE(WritePdag(dir / name, file).ok());
  };
  write("billion.pdag", testing::MinimalMeta(uint64_t{1} << 30, 10), EncodeDag(testing::DenseCube(10), GeometryCoder::kContext).value());
  auto meta = testing::MinimalMeta(4096, 4);
  meta["source"] = {{"points", "many"}};
  write("points.pdag", meta, geometry);
  meta = testing::MinimalMeta(4096, 4);
  meta["codec"] = {{"colors", {{"psnr_y", "high"}}}};
  write("psnr.pdag", meta, geometry);
  const std::string nested = "{\"a\":" + std::string(300000, '[') + std::string(300000, ']') + "}";
  testing::WriteBytes(dir / "nested.pdag", testing::RewrapPdag(nested, geometry));

  const std::pair<const char*, const char*> cases[] = {
      {"billion.pdag", "ResourceLimit: .pdag declares 1073741824 voxels"},
      {"points.pdag", "Corrupt: .pdag metadata 'source/points' is not an integer"},
      {"psnr.pdag", "Corrupt: .pdag metadata 'codec/colors/psnr_y' is not a number"},
      {"nested.pdag", "Corrupt: .pdag metadata is not valid JSON: JSON nested deeper than 64 levels"},
  };
  for (const auto& [name, reason] : cases) {
    const CliRun info = Cli("info " + (dir / name).string(), dir);
    EXPECT_EQ(info.exit_code, 1) << name << ": " << info.err;
    EXPECT_EQ(info.err.rfind(std::string("pointdag: ") + reason, 0), 0u) << name << ": " << info.err;
  }
  // decode reads the metadata it needs the same way; psnr_y is only shown by info.
  EXPECT_EQ(Cli("decode " + (dir / "points.pdag").string() + " -o " + (dir / "x.ply").string(), dir).exit_code, 1);
  const CliRun decode = Cli("decode " + (dir / "psnr.pdag").string() + " -o " + (dir / "x.ply").string(), dir);
  EXPECT_EQ(decode.exit_code, 0) << decode.err;
  EXPECT_NE(decode.err.find("4096 voxels"), std::string::npos) << decode.err;
}

TEST(Cli, VoxelTooSmallIsBadInputWithAReason) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const CliRun run = Cli("encode " + (DataDir() / "tiny_1.2-with-color_1065pts.las").string() + " -o " +
                          (dir / "x.pdag").string() + " --voxel 0.0000001",
                      dir);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("2^21"), std::string::npos) << run.err;
}

// Issue #5's rules without a Vulkan driver (the loader pointed at none): `auto` says so once and
// encodes on the CPU, the same bytes as POINTDAG_DEVICE=cpu; `vulkan` refuses with the reason.
TEST(Cli, WithoutAVulkanDeviceAutoUsesTheCpuAndVulkanIsAClearError) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto scan = (DataDir() / "autzen_trim_pdrf3_rgb.las").string();
  const std::string no_driver = "VK_ICD_FILENAMES=" + (dir / "none.json").string() + " VK_DRIVER_FILES=" + (dir / "none.json").string();
  const std::string args = " --voxel 4 --quality 36";

  const CliRun fallback = Cli("encode " + scan + " -o " + (dir / "auto.pdag").string() + args, dir, no_driver + " POINTDAG_DEVICE=auto");
  ASSERT_EQ(fallback.exit_code, 0) << fallback.err;
  const std::string notice = "no usable Vulkan device";
  const size_t first = fallback.err.find(notice);
  ASSERT_NE(first, std::string::npos) << fallback.err;
  EXPECT_EQ(fallback.err.find(notice, first + 1), std::string::npos) << "said once: " << fallback.err;
  EXPECT_NE(fallback.err.find("running on the CPU"), std::string::npos);

  const CliRun cpu = Cli("encode " + scan + " -o " + (dir / "cpu.pdag").string() + args, dir, "POINTDAG_DEVICE=cpu");
  ASSERT_EQ(cpu.exit_code, 0) << cpu.err;
  EXPECT_EQ(cpu.err.find(notice), std::string::npos) << "cpu never opens Vulkan";
  EXPECT_EQ(testing::ReadBytes(dir / "auto.pdag"), testing::ReadBytes(dir / "cpu.pdag"));

  const CliRun required = Cli("encode " + scan + " -o " + (dir / "vulkan.pdag").string() + args, dir, no_driver + " POINTDAG_DEVICE=vulkan");
  EXPECT_EQ(required.exit_code, 2);
  EXPECT_NE(required.err.find("POINTDAG_DEVICE=vulkan but no Vulkan device could be used"), std::string::npos) << required.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "vulkan.pdag"));

  const CliRun unknown = Cli("encode " + scan + " -o " + (dir / "x.pdag").string() + args, dir, "POINTDAG_DEVICE=gpu");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("POINTDAG_DEVICE must be auto, vulkan or cpu, not 'gpu'"), std::string::npos) << unknown.err;
}

// PCL's reader is a module loaded on first use (read/pcl_reader.h): an ASCII PLY is read through it,
// one our own reader also takes never loads it, and where the module cannot be loaded the PLY that
// needs it is exit 1 naming it, not a crash.
TEST(Cli, AnAsciiPlyIsReadThroughThePclModuleAndItsAbsenceIsAClearError) {
  ScratchDir dir;
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  ply += "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n";
  testing::WriteBytes(dir / "ascii.ply", std::vector<uint8_t>(ply.begin(), ply.end()));
  const std::string encode = "encode " + (dir / "ascii.ply").string() + " --voxel 1 --lossless -o ";
  const CliRun read = Cli(encode + (dir / "a.pdag").string(), dir);
  ASSERT_EQ(read.exit_code, 0) << read.err;
  const CliRun info = Cli("info " + (dir / "a.pdag").string() + " --json", dir);
  EXPECT_EQ(nlohmann::json::parse(info.out, nullptr, false).value("voxels", 0), 3) << info.out;
  EXPECT_NE(info.out.find("\"version\": \"ascii\""), std::string::npos) << info.out;

  const CliRun missing = Cli(encode + (dir / "b.pdag").string(), dir, "POINTDAG_PCL_READER=" + (dir / "none.so").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("needs PCL's reader, libpointdag_pcl_reader.so, which could not be loaded"), std::string::npos)
      << missing.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "b.pdag"));
}

}  // namespace
}  // namespace pointdag
