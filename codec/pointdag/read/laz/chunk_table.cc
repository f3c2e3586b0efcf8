#include "pointdag/read/laz/chunk_table.h"

#include <string>

#include "pointdag/read/byte_io.h"
#include "pointdag/read/laz/integer_decompressor.h"

namespace pointdag::laz {
namespace {

std::string Num(uint64_t v) { return std::to_string(v); }

// The fixed-size chunking the header's count implies: chunk_size points each, the rest in the last.
ChunkTable SequentialChunks(const LaszipVlr& vlr, uint64_t point_count) {
  ChunkTable table;
  table.sequential = true;
  for (uint64_t left = point_count; left > 0;) {
    const uint64_t n = std::min<uint64_t>(left, vlr.chunk_size);
    table.points.push_back(n);
    left -= n;
  }
  return table;
}

// The table at `table_offset`, checked against the chunks it must describe.
StatusOr<ChunkTable> ParseTable(const uint8_t* file, uint64_t first_chunk, uint64_t data_end, uint64_t table_offset,
                                const LaszipVlr& vlr, uint64_t point_count) {
  const uint8_t* t = file + table_offset;
  const uint32_t version = LoadLE<uint32_t>(t);
  const uint32_t count = LoadLE<uint32_t>(t + 4);
  if (version != 0) return Unsupported("LAZ chunk table version " + Num(version) + " is unknown (0 is LASzip's)");
  // Every chunk holds at least one point and at least one byte: bound the count before allocating.
  const uint64_t data_bytes = table_offset - first_chunk;
  if (count == 0 || count > point_count || count > data_bytes) {
    return Malformed("the LAZ chunk table lists " + Num(count) + " chunks for " + Num(point_count) +
                     " points in " + Num(data_bytes) + " bytes");
  }
  ArithmeticDecoder decoder;
  decoder.Init(t + 8, file + data_end);
  IntegerDecompressor sizes(decoder, 32, 2);
  ChunkTable table;
  table.starts.reserve(count + 1);
  table.points.reserve(count);
  table.starts.push_back(first_chunk);
  uint32_t previous_points = 0, previous_bytes = 0;
  uint64_t total_points = 0;
  for (uint32_t i = 0; i < count; ++i) {
    uint64_t points = vlr.chunk_size;
    if (vlr.variable_chunks()) {
      previous_points = static_cast<uint32_t>(sizes.Decompress(static_cast<int32_t>(previous_points), 0));
      points = previous_points;
    } else if (i + 1 == count) {
      points = point_count - total_points;  // fixed chunks: the last one holds the rest
    }
    previous_bytes = static_cast<uint32_t>(sizes.Decompress(static_cast<int32_t>(previous_bytes), 1));
    const uint64_t end = table.starts.back() + previous_bytes;
    if (decoder.overran()) return Truncated("the LAZ chunk table ends early, at chunk " + Num(i) + " of " + Num(count));
    if (points == 0 || points > point_count - total_points || (!vlr.variable_chunks() && points > vlr.chunk_size) ||
        end > table_offset) {
      return Malformed("LAZ chunk table entry " + Num(i) + " (" + Num(points) + " points, " + Num(previous_bytes) +
                       " bytes) does not fit the file's " + Num(point_count) + " points and point data");
    }
    total_points += points;
    table.points.push_back(points);
    table.starts.push_back(end);
  }
  if (total_points != point_count) {
    return Malformed("the LAZ chunk table's chunks hold " + Num(total_points) + " points, the header declares " +
                     Num(point_count));
  }
  return table;
}

}  // namespace

StatusOr<ChunkTable> ReadChunkTable(const uint8_t* file, uint64_t file_size, uint64_t data_offset,
                                    uint64_t data_end, const LaszipVlr& vlr, uint64_t point_count) {
  if (data_end < data_offset + 8) {
    if (point_count == 0) return ChunkTable{};
    return Truncated("the LAZ point data is shorter than its 8-byte chunk table offset");
  }
  const uint64_t first_chunk = data_offset + 8;
  if (point_count == 0) return ChunkTable{{}, {first_chunk}, {}};
  int64_t table_offset = LoadLE<int64_t>(file + data_offset);
  const bool streamed = table_offset == -1;  // the writer could not seek back: maybe a trailer
  if (streamed && file_size >= 8) {
    table_offset = LoadLE<int64_t>(file + file_size - 8);
  } else if (table_offset > 0 && static_cast<uint64_t>(table_offset) >= data_end && data_end == file_size) {
    // The writer knew where its table went: a file that stops before it was cut short.
    return Truncated("the LAZ chunk table should start at byte " + std::to_string(table_offset) +
                     " but the file ends at byte " + Num(file_size) + ": the file is cut short");
  }
  const bool table_inside = table_offset > static_cast<int64_t>(first_chunk) &&
                            static_cast<uint64_t>(table_offset) + 8 <= data_end;
  if (!table_inside && vlr.variable_chunks()) {
    return Malformed("the LAZ chunk table offset " + std::to_string(table_offset) +
                     " lies outside the point data, and variable-size chunks cannot be found without it");
  }
  if (!table_inside) return SequentialChunks(vlr, point_count);
  auto table = ParseTable(file, first_chunk, data_end, static_cast<uint64_t>(table_offset), vlr, point_count);
  // A streamed file's last 8 bytes may be chunk data rather than a trailer: fixed chunks still read.
  if (!table.ok() && streamed && !vlr.variable_chunks()) return SequentialChunks(vlr, point_count);
  return table;
}

}  // namespace pointdag::laz
