// Trains and emits block color stream version 6's fixed weight-group codes (proto/PDAG_FORMAT.md §3,
// proto/tables/block_weight_codes_v6.txt). Not part of the library: the table is frozen once released
// (a new training is a new stream version); this tool shows how it was made and remakes it byte for byte.
//   weight_codes_trainer train OUT.txt SCAN VOXEL [SCAN VOXEL...]
//     Every scan voxelized at VOXEL and cut into tiles by BuildTiles(TilingOptions{}); every tile's
//     colors decoded, and each block's weight groups counted by width and the weight before them.
//     Each code: the Huffman code of counts + 1 (every group gets a code) of at most 12 bits,
//     the counts halved (rounding up) until it fits. The weights are chosen without regard to the
//     codes, so the tiles' stream version does not change the counts.
//   weight_codes_trainer emit TABLE.txt OUT.inc OUT.js
//     The C++ and JavaScript decoders' copies of the table (fixed_weight_codes.inc,
//     web/src/decoder/fixed_weight_codes.js).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "pointdag/color/block_codec.h"
#include "pointdag/color/prefix_weights.h"
#include "pointdag/container/pdag_file.h"
#include "pointdag/pipeline.h"
#include "pointdag/tile/tiler.h"

using namespace pointdag;

namespace {

using GroupCounts = std::array<std::array<std::array<uint64_t, 256>, 17>, 5>;  // [bits][context][symbol]

Status CountScan(const std::string& scan, double voxel, GroupCounts& counts) {
  EncodeOptions options;
  options.voxel_size = voxel;
  ASSIGN_OR_RETURN(const EncodedScan encoded, EncodeScan(scan, options));
  ASSIGN_OR_RETURN(const TileSet tiles, BuildTiles(encoded.grid, ScanInfo{}, "x", TilingOptions{}));
  uint64_t blocks = 0;
  for (const Tile& t : tiles.tiles) {
    ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(t.bytes));
    if (file.colors.empty()) continue;
    ASSIGN_OR_RETURN(const DecodedPdag decoded, DecodePdag(file));
    const uint64_t count = decoded.mip_colors.empty() ? decoded.grid.colors.size() : decoded.mip_colors.size();
    ASSIGN_OR_RETURN(const BlockColorDecoder colors,
                     BlockColorDecoder::Open(std::span(file.colors).subspan(1), count, decoded.grid.morton));
    std::vector<uint8_t> symbols;
    for (size_t k = 0; k < colors.block_count(); ++k, ++blocks) {
      const int bits = colors.BlockBits(k);
      if (!bits) continue;
      const std::vector<uint8_t> weights = colors.BlockWeights(k);
      symbols.clear();
      AppendWeightGroups(weights, bits, symbols);
      const int per = WeightsPerGroup(bits);
      for (size_t g = 0; g < symbols.size(); ++g) ++counts[bits][g ? weights[g * per - 1] : 1 << bits][symbols[g]];
    }
  }
  std::printf("%s %g: %zu tiles, %llu blocks\n", scan.c_str(), voxel, tiles.tiles.size(), static_cast<unsigned long long>(blocks));
  return Status::Ok();
}

int Train(int argc, char** argv) {
  auto counts = std::make_unique<GroupCounts>();
  for (int i = 3; i + 1 < argc; i += 2) {
    const Status s = CountScan(argv[i], std::stod(argv[i + 1]), *counts);
    if (!s.ok()) {
      std::fprintf(stderr, "%s: %s\n", argv[i], s.ToString().c_str());
      return 1;
    }
  }
  std::string text;
  double code_bits = 0, entropy_bits = 0;
  uint64_t groups = 0;
  for (int bits = 1; bits <= 4; ++bits) {
    for (int c = 0; c < GroupContexts(bits); ++c) {
      const int symbols = GroupSymbols(bits);
      std::array<uint64_t, 256> f{};
      uint64_t n = 0;
      for (int s = 0; s < symbols; ++s) {
        f[s] = (*counts)[bits][c][s] + 1;
        n += (*counts)[bits][c][s];
      }
      const std::array<uint8_t, 256> lengths = PrefixCodeLengths(f);  // at most kPrefixCodeBits (12)
      for (int s = 0; s < symbols; ++s) {
        const uint64_t k = (*counts)[bits][c][s];
        text += "0123456789abc"[lengths[s]];
        code_bits += static_cast<double>(k * lengths[s]);
        if (k) entropy_bits -= static_cast<double>(k) * std::log2(static_cast<double>(k) / static_cast<double>(n));
      }
      text += '\n';
      groups += n;
    }
  }
  std::ofstream(argv[2], std::ios::binary) << text;
  std::printf("groups %llu: code %.0f B, entropy %.0f B\n", static_cast<unsigned long long>(groups), code_bits / 8, entropy_bits / 8);
  return 0;
}

int Emit(char** argv) {
  std::ifstream in(argv[2], std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const std::string note = "Generated from proto/tables/block_weight_codes_v6.txt by tools/weight_codes_trainer.cc emit: do not edit.";
  std::ofstream(argv[3], std::ios::binary) << "// " << note << "\nconstexpr char kFixedWeightCodesText[] = R\"table(" << text.str()
                                           << ")table\";\n";
  std::ofstream(argv[4], std::ios::binary) << "// " << note << "\nexport const FIXED_WEIGHT_CODES_TEXT = `" << text.str() << "`;\n";
  return in ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "train" && argc >= 5 && argc % 2 == 1) return Train(argc, argv);
  if (mode == "emit" && argc == 5) return Emit(argv);
  std::fprintf(stderr, "usage: see tools/weight_codes_trainer.cc's first comment\n");
  return 2;
}
