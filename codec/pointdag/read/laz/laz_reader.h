// LAZ (LASzip-compressed LAS, COPC included) reader: streams points like LasReader, decoding the
// chunks of compressed records in parallel.
//
// Contract: the file is mapped read-only; the chunk table bounds each chunk's bytes and a chunk
// decoder (chunk_decoder.h) reads nothing else. A window of chunks is decoded at once (TBB), each
// at most kPieceBytes of records ahead of the reader, so memory stays bounded whatever the chunk
// sizes. Points come out in file order, so the records equal the decompressed LAS's exactly. Any
// decoding failure is a status that names the chunk ("chunk 3 of 11 (points 150000-199999) ...").
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include "pointdag/read/las_header.h"
#include "pointdag/read/laz/chunk_decoder.h"
#include "pointdag/read/laz/chunk_table.h"
#include "pointdag/read/scan_reader.h"

namespace pointdag::laz {

class LazReader final : public ScanReader {
 public:
  static StatusOr<std::unique_ptr<LazReader>> Open(const std::filesystem::path& path);
  ~LazReader() override;

  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override;
  Status Rewind() override;
  // The next up to max_points decompressed records (record_length bytes each), appended to `out`.
  StatusOr<size_t> ReadRecords(std::vector<uint8_t>& out, size_t max_points);

  const LaszipVlr& vlr() const { return vlr_; }
  const ChunkTable& chunks() const { return chunks_; }
  uint32_t record_length() const { return layout_.record_length; }

 private:
  struct Slot;  // one chunk being decoded
  LazReader();
  Status OpenSlots();
  Status Refill();
  StatusOr<size_t> Next(size_t max_points, const uint8_t*& records);

  std::string path_;
  const uint8_t* file_ = nullptr;  // the mapping
  uint64_t file_size_ = 0;
  LasHeader header_;
  LasRecordLayout layout_;
  LaszipVlr vlr_;
  ChunkTable chunks_;
  size_t window_ = 1;
  std::vector<std::unique_ptr<Slot>> slots_;  // the chunks in flight, in file order
  std::vector<std::unique_ptr<Slot>> spare_;  // finished slots, kept for their decoders
  size_t next_chunk_ = 0;                     // the next chunk to give a slot
  uint64_t next_sequential_start_ = 0;        // without a table: where the next chunk starts
  uint64_t next_point_ = 0;
};

// Every decompressed point record of a LAZ file, in order (what `laszip -i f.laz -o f.las` writes
// after the header): for tests against other implementations and for the benchmark.
StatusOr<std::vector<uint8_t>> DecodeAllRecords(const std::filesystem::path& path);

}  // namespace pointdag::laz
