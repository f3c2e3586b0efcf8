#include "pointdag/read/laz/laz_reader.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "pointdag/read/laz/copc_info.h"

namespace pointdag::laz {
namespace {

// Records decoded ahead per chunk: whole chunks of the usual 50,000 points, bounded memory for huge ones.
constexpr size_t kPieceBytes = size_t{4} << 20;

std::string Num(uint64_t v) { return std::to_string(v); }

std::string Describe(const LaszipVlr& vlr, const ChunkTable& chunks) {
  std::string s = "LASzip " + Num(vlr.version_major) + "." + Num(vlr.version_minor) + "r" +
                  Num(vlr.version_revision) +
                  (vlr.compressor == Compressor::kLayeredChunked ? " layered, " : " point-wise, ") +
                  Num(chunks.size()) + (vlr.variable_chunks() ? " variable" : "") + " chunks" +
                  (chunks.sequential ? " (no chunk table)" : "") + ":";
  for (const Item& item : vlr.items) s += " " + ItemName(item);
  return s;
}

}  // namespace

struct LazReader::Slot {
  size_t chunk = 0;
  uint64_t first_point = 0;  // the chunk's first point in the file
  uint64_t start = 0, end = 0;  // the chunk's bytes
  uint64_t left = 0;            // points not yet decoded
  bool started = false;
  std::unique_ptr<ChunkDecoder> decoder;
  std::vector<uint8_t> records;
  size_t ready = 0, taken = 0;  // records decoded into `records`, and handed out
  Status status;
};

LazReader::LazReader() = default;

LazReader::~LazReader() {
  if (file_) munmap(const_cast<uint8_t*>(file_), file_size_);
}

StatusOr<std::unique_ptr<LazReader>> LazReader::Open(const std::filesystem::path& path) {
  std::unique_ptr<LazReader> reader(new LazReader());
  reader->path_ = path.string();
  std::FILE* f = std::fopen(reader->path_.c_str(), "rb");
  if (!f) return IoError("cannot open " + reader->path_);
  std::error_code ec;
  reader->file_size_ = std::filesystem::file_size(path, ec);
  auto header = ec ? StatusOr<LasHeader>(IoError("cannot stat " + reader->path_ + ": " + ec.message()))
                   : ReadLasHeader(f, reader->file_size_, reader->info_, reader->layout_);
  if (header.ok()) {
    void* map = mmap(nullptr, reader->file_size_, PROT_READ, MAP_PRIVATE, fileno(f), 0);
    if (map != MAP_FAILED) reader->file_ = static_cast<const uint8_t*>(map);
  }
  std::fclose(f);
  if (!header.ok()) return header.status();
  if (!reader->file_) return IoError("cannot map " + reader->path_ + " into memory");
  reader->header_ = std::move(*header);
  const LasHeader& h = reader->header_;
  if (!h.compressed) return InvalidArgument(reader->path_ + " is a plain LAS file, not LAZ");
  if (!h.laszip_vlr) return Malformed("the point format says LAZ but the file has no LASzip VLR");
  ASSIGN_OR_RETURN(reader->vlr_, ParseLaszipVlr(*h.laszip_vlr, h.record_length));
  ASSIGN_OR_RETURN(reader->chunks_, ReadChunkTable(reader->file_, reader->file_size_, h.point_data_offset,
                                                   h.point_data_end, reader->vlr_, h.point_count));
  reader->info_.compression = Describe(reader->vlr_, reader->chunks_);
  if (h.copc_info) {
    reader->info_.copc = ReadCopcHierarchy(*h.copc_info, reader->file_, reader->file_size_, h.point_count);
  }
  reader->window_ = reader->chunks_.sequential
                        ? 1
                        : static_cast<size_t>(std::max(2, 2 * tbb::this_task_arena::max_concurrency()));
  RETURN_IF_ERROR(reader->Rewind());
  return reader;
}

Status LazReader::Rewind() {
  for (auto& slot : slots_) spare_.push_back(std::move(slot));
  slots_.clear();
  next_chunk_ = 0;
  next_point_ = 0;
  next_sequential_start_ = header_.point_data_offset + 8;
  return OpenSlots();
}

// Gives the next chunks a slot each, up to the window.
Status LazReader::OpenSlots() {
  while (slots_.size() < window_ && next_chunk_ < chunks_.size()) {
    // Slots (and their decoders' models) are reused: COPC files have thousands of small chunks.
    std::unique_ptr<Slot> slot;
    if (spare_.empty()) {
      slot = std::make_unique<Slot>();
      ASSIGN_OR_RETURN(slot->decoder, MakeChunkDecoder(vlr_));
    } else {
      slot = std::move(spare_.back());
      spare_.pop_back();
      slot->started = false;
      slot->ready = slot->taken = 0;
      slot->status = Status::Ok();
    }
    slot->chunk = next_chunk_;
    slot->first_point = next_point_;
    for (const auto& s : slots_) slot->first_point += s->left + (s->ready - s->taken);
    slot->left = chunks_.points[next_chunk_];
    if (chunks_.sequential) {
      slot->start = next_sequential_start_;
      slot->end = header_.point_data_end;
    } else {
      slot->start = chunks_.starts[next_chunk_];
      slot->end = chunks_.starts[next_chunk_ + 1];
    }
    slots_.push_back(std::move(slot));
    ++next_chunk_;
  }
  return Status::Ok();
}

// Decodes the next piece of every slot whose records are all handed out, in parallel.
Status LazReader::Refill() {
  std::vector<Slot*> hungry;
  for (auto& s : slots_) {
    if (s->taken == s->ready && s->left > 0) hungry.push_back(s.get());
  }
  const size_t piece_points = std::max<size_t>(1, kPieceBytes / layout_.record_length);
  tbb::parallel_for(size_t{0}, hungry.size(), [&](size_t i) {
    Slot& s = *hungry[i];
    if (!s.started) {
      s.status = s.decoder->Start(file_ + s.start, s.end - s.start, s.left);
      s.started = true;
      if (!s.status.ok()) return;
    }
    const size_t n = static_cast<size_t>(std::min<uint64_t>(s.left, piece_points));
    s.records.resize(n * layout_.record_length);
    s.status = s.decoder->Decode(s.records.data(), n);
    s.ready = n;
    s.taken = 0;
    s.left -= n;
  });
  for (Slot* s : hungry) {
    if (!s->status.ok()) {
      const uint64_t points = chunks_.points[s->chunk];
      return Status(s->status.code(), "LAZ chunk " + Num(s->chunk) + " of " + Num(chunks_.size()) + " (points " +
                                          Num(s->first_point) + "-" + Num(s->first_point + points - 1) + ", bytes " +
                                          Num(s->start) + "-" + Num(s->end) + "): " + s->status.message());
    }
  }
  return Status::Ok();
}

StatusOr<size_t> LazReader::Next(size_t max_points, const uint8_t*& records) {
  while (!slots_.empty()) {
    Slot& s = *slots_.front();
    if (s.taken < s.ready) {
      const size_t n = std::min(max_points, s.ready - s.taken);
      records = s.records.data() + s.taken * layout_.record_length;
      s.taken += n;
      next_point_ += n;
      return n;
    }
    if (s.left > 0) {
      RETURN_IF_ERROR(Refill());
      continue;
    }
    if (chunks_.sequential) next_sequential_start_ = s.start + s.decoder->BytesUsed();
    spare_.push_back(std::move(slots_.front()));
    slots_.erase(slots_.begin());
    RETURN_IF_ERROR(OpenSlots());
  }
  return size_t{0};
}

StatusOr<size_t> LazReader::Read(PointBatch& batch, size_t max_points) {
  batch.clear();
  size_t total = 0;
  while (total < max_points) {
    const uint8_t* records = nullptr;
    const uint64_t first = next_point_;
    ASSIGN_OR_RETURN(size_t n, Next(max_points - total, records));
    if (n == 0) break;
    RETURN_IF_ERROR(layout_.Append(records, n, first, batch, max_color_seen_));
    total += n;
  }
  return total;
}

StatusOr<size_t> LazReader::ReadRecords(std::vector<uint8_t>& out, size_t max_points) {
  size_t total = 0;
  while (total < max_points) {
    const uint8_t* records = nullptr;
    ASSIGN_OR_RETURN(size_t n, Next(max_points - total, records));
    if (n == 0) break;
    out.insert(out.end(), records, records + n * layout_.record_length);
    total += n;
  }
  return total;
}

StatusOr<std::vector<uint8_t>> DecodeAllRecords(const std::filesystem::path& path) {
  ASSIGN_OR_RETURN(auto reader, LazReader::Open(path));
  std::vector<uint8_t> records;
  for (;;) {
    ASSIGN_OR_RETURN(size_t n, reader->ReadRecords(records, size_t{1} << 20));
    if (n == 0) break;
  }
  return records;
}

}  // namespace pointdag::laz
