// One case of the nightly benchmark: a scan at one voxel size, coded by us and by Draco in the same
// process, sizes, qualities and speeds as JSON (the schema: docs/nightly.md).
//
// Sizes and qualities are `pointdag compare`'s scorecard (codec/pointdag/compare/scorecard.h) for the
// same scan and voxel size, so they equal what `pointdag compare --voxel S --json` prints. Per case:
// VBR, fixed3 and hierarchical at every target, the smallest image mapping that met each target, lossless colors;
// speeds in voxels per second on the same voxels: our encode (DAG, stored geometry, VBR colors at
// 38 dB) and decode (the whole .pdag back to voxels and colors) against Draco's -cl 10 encode and its
// decode; the process's peak RSS.
#pragma once

#include <nlohmann/json.hpp>

#include "pointdag/bench/corpus.h"

namespace pointdag {

// Never fails: a case that cannot run is {"scan", "voxel", "error"}.
nlohmann::json RunCorpusCase(const CorpusCase& c);

// The rows of "ours" that a report compares and tabulates, with a key naming each ("vbr@38",
// "fixed3@34", "image@42", "lossless").
std::string CodecRowKey(const nlohmann::json& row);

// A number member of a report's object, NaN when it is absent or not a number (null for a
// lossless PSNR, or missing in an older report); NaN compares false, so such values never regress.
double JsonNumber(const nlohmann::json& object, const char* key);

}  // namespace pointdag
