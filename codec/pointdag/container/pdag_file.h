// Stage 6: the .pdag container (normative layout: proto/PDAG_FORMAT.md).
//
// A fixed header (magic, version, section count, file size, header CRC), a table of sections
// (tag, offset, length, CRC32C), then the sections: "meta" (JSON), "geometry" (the DAG's stored
// form) and "colors" (voxel colors in color-index order). Readers check every length against the
// real size and every CRC before handing out a byte; writers write to a temporary file and rename
// it, so a crash never leaves a half-written .pdag under the final name.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pointdag/status.h"

namespace pointdag {

constexpr uint16_t kPdagMajorVersion = 1;
constexpr uint16_t kPdagMinorVersion = 0;

struct PdagFile {
  nlohmann::json meta = nlohmann::json::object();
  std::vector<uint8_t> geometry;
  std::vector<uint8_t> colors;  // empty when the scan had no color
};

std::vector<uint8_t> SerializePdag(const PdagFile& file);
StatusOr<PdagFile> ParsePdag(std::span<const uint8_t> bytes);

Status WritePdag(const std::filesystem::path& path, const PdagFile& file);
StatusOr<PdagFile> ReadPdag(const std::filesystem::path& path);

// Reads a whole file into memory (kIoError naming the path on failure).
StatusOr<std::vector<uint8_t>> ReadFileBytes(const std::filesystem::path& path);
// Writes to `path`.tmp-XXXX, fsyncs, then renames over `path`.
Status WriteFileAtomically(const std::filesystem::path& path, std::span<const uint8_t> bytes);

}  // namespace pointdag
