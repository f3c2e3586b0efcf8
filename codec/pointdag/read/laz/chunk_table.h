// The LAZ chunk table: where each chunk of compressed points starts and how many points it holds.
//
// The point data begins with the table's file offset (int64). The table holds a version (0), the
// chunk count and, arithmetic-coded, each chunk's byte size (and, for variable chunks, its point
// count) as a difference to the previous chunk's. A writer that could not seek back stores -1
// there and the offset in the file's last 8 bytes.
//
// Contract: ReadChunkTable() checks the count before allocating (never more chunks than points or
// than bytes), checks that the chunks tile the point data exactly and that their points add up to
// the header's count. A table offset past the end of the file means the file was cut short
// (Truncated). A missing table (offset -1 without a trailer) is not an error for fixed-size chunks:
// the result is then `sequential`, and the reader finds each chunk's end by decoding the one before.
#pragma once

#include <cstdint>
#include <vector>

#include "pointdag/read/laz/laszip_vlr.h"
#include "pointdag/status.h"

namespace pointdag::laz {

struct ChunkTable {
  bool sequential = false;       // no usable table: chunks are found one after the other
  std::vector<uint64_t> starts;  // absolute file offset of each chunk, plus one past the last one's end
  std::vector<uint64_t> points;  // points of each chunk
  size_t size() const { return points.size(); }
};

// `file` is the whole file's bytes; the point data lies in [data_offset, data_end).
StatusOr<ChunkTable> ReadChunkTable(const uint8_t* file, uint64_t file_size, uint64_t data_offset,
                                    uint64_t data_end, const LaszipVlr& vlr, uint64_t point_count);

}  // namespace pointdag::laz
