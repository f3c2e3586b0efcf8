// 3D Tiles 1.1 (codec/pointdag/tiles3d/): the .glb of a tile read back as a runtime reads it, the
// tileset's invariants on a real scan's tiles, and `pointdag export --3dtiles` from a .pdag.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <random>

#include "glb_reader.h"
#include "pointdag/ingest.h"
#include "pointdag/tiles3d/glb_writer.h"
#include "pointdag/tiles3d/tile_content.h"
#include "pointdag/tiles3d/tileset.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::Cli;
using testing::CliRun;
using testing::DataDir;
using testing::ReadGlb;
using testing::ScratchDir;

// Within a few thousand ulps of the magnitude: far below any voxel.
bool Near(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(1.0, std::abs(b)); }

// Every point of the glb is the centre of the grid's voxel at the same index, with its color.
void ExpectGlbHoldsGrid(const std::vector<uint8_t>& glb, const VoxelGrid& grid) {
  const testing::GlbPoints read = ReadGlb(glb);
  ASSERT_EQ(read.positions.size(), grid.morton.size());
  EXPECT_TRUE(read.padding_zero);
  for (size_t i = 0; i < grid.morton.size(); ++i) {
    const auto centre = grid.VoxelCentre(grid.morton[i]);
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(Near(read.positions[i][a], centre[a])) << i << " axis " << a << ": " << read.positions[i][a] << " vs " << centre[a];
  }
  EXPECT_EQ(read.colors, grid.colors);
  EXPECT_EQ(read.gltf["meshes"][0]["primitives"][0]["attributes"].contains("COLOR_0"), grid.has_color());
}

VoxelGrid SyntheticTile(bool colors) {
  VoxelGrid grid;
  grid.depth = 8;
  grid.origin = {652000.25, 4500000.5, -12.0};  // far from zero, as a projected CRS is
  grid.voxel_size = 0.3;
  grid.morton = testing::SurfaceVoxels(8, 5000, 7);
  std::mt19937 rng(3);
  if (colors) {
    for (size_t i = 0; i < grid.morton.size(); ++i) {
      grid.colors.push_back({static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng())});
    }
  }
  return grid;
}

TEST(Glb, PointsAreTheVoxelCentresAndColors) {
  const VoxelGrid grid = SyntheticTile(true);
  const auto glb = WriteTileGlb(grid);
  ASSERT_TRUE(glb.ok()) << glb.status().ToString();
  ExpectGlbHoldsGrid(*glb, grid);
  // Same grid, same bytes: the daemon and the CLI agree by construction.
  EXPECT_EQ(*WriteTileGlb(grid), *glb);
}

TEST(Glb, TileWithoutColorsHasNoColor0) {
  const VoxelGrid grid = SyntheticTile(false);
  const auto glb = WriteTileGlb(grid);
  ASSERT_TRUE(glb.ok()) << glb.status().ToString();
  ExpectGlbHoldsGrid(*glb, grid);
  EXPECT_EQ(ReadGlb(*glb).gltf["accessors"].size(), 1u);
}

TEST(Glb, NodeMatrixTurnsDatasetFrameToGltfYUp) {
  // A cell c lands at (wx, wz, -wy), w = origin + (c + 0.5) s; the matrix is a rotation times a
  // uniform scale (decomposable to TRS, as glTF requires).
  const auto m = TileNodeMatrix({10, 20, 30}, 2);
  EXPECT_EQ(m, (std::array<double, 16>{2, 0, 0, 0, 0, 0, -2, 0, 0, 2, 0, 0, 11, 31, -21, 1}));
  EXPECT_FALSE(std::signbit(TileNodeMatrix({0, -1, 0}, 2)[14]));  // 0.0, never -0.0
}

TEST(Glb, RefusesWhatItCannotWrite) {
  VoxelGrid empty;
  EXPECT_EQ(WriteTileGlb(empty).status().code(), StatusCode::kInvalidArgument);
  VoxelGrid deep = SyntheticTile(false);
  deep.depth = 17;
  EXPECT_EQ(WriteTileGlb(deep).status().code(), StatusCode::kInvalidArgument);
  VoxelGrid short_colors = SyntheticTile(true);
  short_colors.colors.pop_back();
  EXPECT_EQ(WriteTileGlb(short_colors).status().code(), StatusCode::kInvalidArgument);
}

TilesetDataset Described(const IngestedScan& scan) {
  TilesetDataset d;
  d.origin = scan.grid.origin;
  d.voxel_size = scan.grid.voxel_size;
  d.levels = scan.tiles.levels;
  d.tile_depth = scan.tiles.tile_depth;
  if (scan.frame.georeferenced) d.enu_to_ecef = scan.frame.enu_to_ecef;
  return d;
}

// Autzen through the daemon's pipeline at 0.25 m: 4 levels, georeferenced.
const IngestedScan& Autzen() {
  static const IngestedScan scan = [] {
    IngestOptions options;
    options.voxel_size = 0.25;
    auto ingested = IngestScan(DataDir() / "autzen_trim_pdrf3_rgb.las", options);
    EXPECT_TRUE(ingested.ok()) << ingested.status().ToString();
    return ingested.ok() ? std::move(*ingested) : IngestedScan{};
  }();
  return scan;
}

TEST(TileContent, RealTilesTranscodeToTheirDecodedVoxels) {
  SKIP_WITHOUT_DATA();
  const IngestedScan& scan = Autzen();
  ASSERT_GE(scan.tiles.levels, 3);
  for (const Tile& tile : scan.tiles.tiles) {
    SCOPED_TRACE(ContentUri(tile.key));
    const auto decoded = DecodePdag(*ParsePdag(tile.bytes));
    ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
    const auto content = TranscodeTile(tile.key, tile.bytes, scan.tiles.tile_depth);
    ASSERT_TRUE(content.ok()) << content.status().ToString();
    ExpectGlbHoldsGrid(content->glb, decoded->grid);
    const auto measured = MeasureStoredTile(tile.key, tile.bytes, scan.tiles.tile_depth);
    ASSERT_TRUE(measured.ok());
    EXPECT_EQ(measured->min, content->box.min);
    EXPECT_EQ(measured->max, content->box.max);
  }
  // A tile is refused at another tile depth than its own.
  EXPECT_EQ(TranscodeTile({}, scan.tiles.tiles[0].bytes, 7).status().code(), StatusCode::kCorrupt);
}

TEST(Tileset, BoxesAreTightAndNestedErrorsDecreaseTransformIsEnuToEcef) {
  SKIP_WITHOUT_DATA();
  const IngestedScan& scan = Autzen();
  ASSERT_TRUE(scan.frame.georeferenced);
  const TilesetDataset dataset = Described(scan);
  std::vector<TileBox> boxes;
  std::map<std::string, VoxelGrid> grids;  // by content uri
  for (const Tile& tile : scan.tiles.tiles) {
    boxes.push_back(*MeasureStoredTile(tile.key, tile.bytes, dataset.tile_depth));
    grids[ContentUri(tile.key)] = DecodePdag(*ParsePdag(tile.bytes))->grid;
  }
  const auto text = BuildTileset(dataset, boxes);
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  const nlohmann::json tileset = nlohmann::json::parse(*text);
  EXPECT_EQ(tileset["asset"]["version"], "1.1");
  const nlohmann::json& root = tileset["root"];
  EXPECT_EQ(root["transform"].get<std::vector<double>>(), std::vector<double>(scan.frame.enu_to_ecef.begin(), scan.frame.enu_to_ecef.end()));
  EXPECT_EQ(root["refine"], "REPLACE");
  EXPECT_EQ(root["content"]["uri"], "0/0/0/0.glb");
  EXPECT_GT(tileset["geometricError"].get<double>(), root["geometricError"].get<double>());

  std::map<std::string, int> seen;
  using Box = std::array<double, 6>;
  const std::function<void(const nlohmann::json&, const Box*, double, int)> walk = [&](const nlohmann::json& tile, const Box* parent,
                                                                                      double parent_error, int level) {
    const std::string uri = tile["content"]["uri"];
    SCOPED_TRACE(uri);
    ++seen[uri];
    EXPECT_EQ(uri.substr(0, uri.find('/')), std::to_string(level));
    const auto b = tile["boundingVolume"]["box"].get<std::array<double, 12>>();
    EXPECT_EQ(b[4], 0);  // axis-aligned half axes
    EXPECT_EQ(b[8], 0);
    const Box box{b[0] - b[3], b[1] - b[7], b[2] - b[11], b[0] + b[3], b[1] + b[7], b[2] + b[11]};
    const double error = tile["geometricError"];
    EXPECT_EQ(error, level == dataset.levels - 1 ? 0.0 : dataset.LevelVoxelSize(level));
    if (parent) {
      EXPECT_LT(error, parent_error);
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(box[a], (*parent)[a]) << "axis " << a;
        EXPECT_LE(box[3 + a], (*parent)[3 + a]) << "axis " << a;
      }
    }
    // The box holds every voxel of the tile (whole cubes) and touches the outermost on each side.
    const VoxelGrid& grid = grids.at(uri);
    Box extent{1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
    for (uint64_t code : grid.morton) {
      const auto c = grid.VoxelCentre(code);
      for (int a = 0; a < 3; ++a) {
        extent[a] = std::min(extent[a], c[a] - grid.voxel_size / 2);
        extent[3 + a] = std::max(extent[3 + a], c[a] + grid.voxel_size / 2);
      }
    }
    for (int k = 0; k < 6; ++k) EXPECT_TRUE(Near(box[k], extent[k])) << k << ": " << box[k] << " vs " << extent[k];
    if (tile.contains("children")) {
      for (const nlohmann::json& child : tile["children"]) walk(child, &box, error, level + 1);
    }
  };
  walk(root, nullptr, 0, 0);
  EXPECT_EQ(seen.size(), scan.tiles.tiles.size());
  for (const auto& [uri, n] : seen) EXPECT_EQ(n, 1) << uri;
  // The finest tiles are the deepest and have no error.
  EXPECT_EQ(std::count_if(seen.begin(), seen.end(), [&](const auto& s) { return s.first[0] - '0' == dataset.levels - 1; }),
            std::count_if(scan.tiles.tiles.begin(), scan.tiles.tiles.end(), [&](const Tile& t) { return t.key.level == dataset.levels - 1; }));
}

TEST(Tileset, WithoutCrsTheTransformIsIdentityWithANote) {
  const auto dataset = ParseTilesetDataset(nlohmann::json::parse(
      R"({"bounds": {"min": [1, 2, 3]}, "voxel_size": 0.5, "levels": 2, "tile_depth": 8, "frame": {"georeferenced": false}})"));
  ASSERT_TRUE(dataset.ok()) << dataset.status().ToString();
  EXPECT_FALSE(dataset->enu_to_ecef);
  const auto text = BuildTileset(*dataset, {TileBox{{0, 0, 0, 0}, {0, 0, 0}, {9, 9, 9}}, TileBox{{1, 1, 0, 0}, {256, 0, 0}, {300, 3, 3}}});
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  const nlohmann::json tileset = nlohmann::json::parse(*text);
  EXPECT_EQ(tileset["root"]["transform"], nlohmann::json({1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0}));
  EXPECT_NE(tileset["asset"]["extras"]["pointdag"]["frame"].get<std::string>().find("no CRS"), std::string::npos);
  // Root: level 0, voxel 1.0, cells 0..9 -> [1, 11); child: level 1, voxel 0.5, x cells 256..300 -> [129, 151.5).
  EXPECT_EQ(tileset["root"]["boundingVolume"]["box"], nlohmann::json({6.0, 7.0, 8.0, 5.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 5.0}));
  EXPECT_EQ(tileset["root"]["children"][0]["boundingVolume"]["box"],
            nlohmann::json({140.25, 3.0, 4.0, 11.25, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}));
  EXPECT_EQ(tileset["root"]["geometricError"], 1.0);
  EXPECT_EQ(tileset["geometricError"], 2.0);
  EXPECT_EQ(tileset["root"]["children"][0]["content"]["uri"], "1/1/0/0.glb");
}

TEST(Tileset, RefusesWhatIsNotOneTree) {
  TilesetDataset d;
  d.voxel_size = 1;
  d.levels = 3;
  d.tile_depth = 8;
  const TileBox root{{0, 0, 0, 0}, {}, {}};
  EXPECT_EQ(BuildTileset(d, {}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildTileset(d, {TileBox{{1, 0, 0, 0}, {}, {}}}).status().code(), StatusCode::kInvalidArgument);  // no root
  EXPECT_EQ(BuildTileset(d, {root, TileBox{{2, 0, 0, 0}, {}, {}}}).status().code(), StatusCode::kInvalidArgument);  // orphan
  EXPECT_EQ(BuildTileset(d, {root, TileBox{{3, 0, 0, 0}, {}, {}}}).status().code(), StatusCode::kInvalidArgument);  // past the levels
  EXPECT_EQ(BuildTileset(d, {root, TileBox{{1, 2, 0, 0}, {}, {}}}).status().code(), StatusCode::kInvalidArgument);  // outside level 1
  EXPECT_EQ(BuildTileset(d, {root, root}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(BuildTileset(d, {root, TileBox{{1, 1, 1, 1}, {}, {}}}).ok());
}

TEST(Tileset, RefusesMalformedDescriptions) {
  const auto parse = [](const std::string& frame, const std::string& voxel = "0.5") {
    return ParseTilesetDataset(nlohmann::json::parse(R"({"bounds": {"min": [1, 2, 3]}, "voxel_size": )" + voxel +
                                                     R"(, "levels": 2, "tile_depth": 8, "frame": )" + frame + "}"))
        .status()
        .code();
  };
  const std::string m15 = "[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0]";
  EXPECT_EQ(parse(R"({"georeferenced": false})"), StatusCode::kOk);
  EXPECT_EQ(parse(R"({"georeferenced": false})", "-1"), StatusCode::kMalformed);
  EXPECT_EQ(parse(R"({})"), StatusCode::kMalformed);
  EXPECT_EQ(parse(R"({"georeferenced": 1})"), StatusCode::kMalformed);
  EXPECT_EQ(parse(R"({"georeferenced": true})"), StatusCode::kMalformed);
  EXPECT_EQ(parse(R"({"georeferenced": true, "enu_to_ecef": )" + m15 + "}"), StatusCode::kMalformed);
  EXPECT_EQ(parse(R"({"georeferenced": true, "enu_to_ecef": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,"1"]})"), StatusCode::kMalformed);
  EXPECT_EQ(parse(R"({"georeferenced": true, "enu_to_ecef": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]})"), StatusCode::kOk);
}

// Every content of an exported tileset, by uri, with the finest level's points gathered.
struct Exported {
  nlohmann::json tileset;
  std::map<std::string, testing::GlbPoints> contents;
  std::vector<std::array<double, 3>> finest_points;
};

Exported ReadExport(const std::filesystem::path& dir, int finest_level) {
  Exported out;
  out.tileset = nlohmann::json::parse(testing::ReadBytes(dir / "tileset.json"));
  const std::function<void(const nlohmann::json&)> walk = [&](const nlohmann::json& tile) {
    const std::string uri = tile["content"]["uri"];
    testing::GlbPoints points = ReadGlb(testing::ReadBytes(dir / uri));
    if (uri[0] - '0' == finest_level) out.finest_points.insert(out.finest_points.end(), points.positions.begin(), points.positions.end());
    out.contents[uri] = std::move(points);
    if (tile.contains("children")) {
      for (const nlohmann::json& child : tile["children"]) walk(child);
    }
  };
  walk(out.tileset["root"]);
  return out;
}

TEST(Export3dTiles, FromAGeoreferencedPdagTheFinestLevelIsItsVoxels) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto pdag = dir / "a.pdag";
  const CliRun encode = Cli("encode " + (DataDir() / "autzen_trim_pdrf3_rgb.las").string() + " -o " + pdag.string() +
                                " --voxel 0.5 --georeference", dir);
  ASSERT_EQ(encode.exit_code, 0) << encode.err;
  const CliRun run = Cli("export " + pdag.string() + " --3dtiles " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find(" tiles, "), std::string::npos) << run.err;

  const PdagFile file = *ReadPdag(pdag);
  const VoxelGrid grid = DecodePdag(file)->grid;
  const int levels = grid.depth - 8 + 1;
  const Exported exported = ReadExport(dir / "out", levels - 1);
  EXPECT_EQ(exported.tileset["root"]["transform"], file.meta["frame"]["enu_to_ecef"]);
  size_t files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir / "out")) files += entry.path().extension() == ".glb";
  EXPECT_EQ(files, exported.contents.size());

  std::vector<std::array<double, 3>> expected, got = exported.finest_points;
  for (uint64_t code : grid.morton) expected.push_back(grid.VoxelCentre(code));
  ASSERT_EQ(got.size(), expected.size());
  std::sort(expected.begin(), expected.end());
  std::sort(got.begin(), got.end());
  for (size_t i = 0; i < got.size(); ++i) {
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(Near(got[i][a], expected[i][a])) << i;
  }
}

TEST(Export3dTiles, FromAPdagWithoutCrsTheTransformIsIdentity) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  const auto pdag = dir / "tiny.pdag";
  ASSERT_EQ(Cli("encode " + (DataDir() / "tiny_1.2-with-color_1065pts.las").string() + " -o " + pdag.string() + " --voxel 2", dir).exit_code, 0);
  const CliRun run = Cli("export " + pdag.string() + " --3dtiles " + (dir / "out").string(), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json tileset = nlohmann::json::parse(testing::ReadBytes(dir / "out" / "tileset.json"));
  EXPECT_EQ(tileset["root"]["transform"], nlohmann::json({1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0}));

  const CliRun missing = Cli("export " + (dir / "none.pdag").string() + " --3dtiles " + (dir / "x").string(), dir);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("none.pdag"), std::string::npos) << missing.err;
  EXPECT_EQ(Cli("export " + pdag.string(), dir).exit_code, 2);  // --3dtiles is required
}

}  // namespace
}  // namespace pointdag
