#include "pointdag/container/pdag_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "pointdag/container/crc32c.h"
#include "pointdag/json_text.h"
#include "pointdag/read/byte_io.h"

namespace pointdag {
namespace {

constexpr uint8_t kMagic[8] = {'P', 'D', 'A', 'G', '\r', '\n', 0x1A, '\n'};
constexpr size_t kHeaderSize = 32;
constexpr size_t kEntrySize = 32;
constexpr uint32_t kMaxSections = 64;

struct Section {
  std::string tag;
  std::span<const uint8_t> data;
};

std::string TagString(const uint8_t* p) { return FixedString(p, 8); }

// CRC over the header (with its own CRC field zeroed) and the section table, in three runs: no copy.
uint32_t HeaderCrc(std::span<const uint8_t> header_and_table) {
  constexpr uint8_t kZeroField[4] = {};
  const uint32_t head = Crc32c(header_and_table.first(16));
  return Crc32c(header_and_table.subspan(20), Crc32c(kZeroField, head));
}

}  // namespace

std::vector<uint8_t> SerializePdag(const PdagFile& file) {
  const std::string meta = DumpJson(file.meta);
  std::vector<Section> sections = {
      {"meta", {reinterpret_cast<const uint8_t*>(meta.data()), meta.size()}},
      {"geometry", file.geometry},
  };
  if (!file.colors.empty()) sections.push_back({"colors", file.colors});

  std::vector<uint8_t> out(kMagic, kMagic + 8);
  AppendLE<uint16_t>(out, kPdagMajorVersion);
  AppendLE<uint16_t>(out, kPdagMinorVersion);
  AppendLE<uint32_t>(out, static_cast<uint32_t>(sections.size()));
  AppendLE<uint32_t>(out, 0);  // header CRC, filled below
  AppendLE<uint32_t>(out, 0);  // reserved
  uint64_t total = kHeaderSize + kEntrySize * sections.size();
  for (const auto& s : sections) total += s.data.size();
  AppendLE<uint64_t>(out, total);

  uint64_t offset = kHeaderSize + kEntrySize * sections.size();
  for (const auto& s : sections) {
    uint8_t tag[8] = {};
    std::memcpy(tag, s.tag.data(), std::min<size_t>(8, s.tag.size()));
    out.insert(out.end(), tag, tag + 8);
    AppendLE<uint64_t>(out, offset);
    AppendLE<uint64_t>(out, s.data.size());
    AppendLE<uint32_t>(out, Crc32c(s.data));
    AppendLE<uint32_t>(out, 0);  // flags
    offset += s.data.size();
  }
  const uint32_t crc = HeaderCrc(out);
  std::memcpy(out.data() + 16, &crc, 4);
  for (const auto& s : sections) out.insert(out.end(), s.data.begin(), s.data.end());
  return out;
}

StatusOr<PdagFile> ParsePdag(std::span<const uint8_t> bytes) {
  if (bytes.size() < kHeaderSize) return Truncated("file is shorter than the 32-byte .pdag header");
  if (std::memcmp(bytes.data(), kMagic, 8) != 0) return Corrupt("not a .pdag file (wrong magic)");
  const auto major = LoadLE<uint16_t>(bytes.data() + 8);
  const auto minor = LoadLE<uint16_t>(bytes.data() + 10);
  if (major != kPdagMajorVersion) {
    return Unsupported(".pdag version " + std::to_string(major) + "." + std::to_string(minor) +
                       " is not supported (this build reads version 1.x)");
  }
  const auto count = LoadLE<uint32_t>(bytes.data() + 12);
  const auto header_crc = LoadLE<uint32_t>(bytes.data() + 16);
  const auto total = LoadLE<uint64_t>(bytes.data() + 24);
  if (count == 0 || count > kMaxSections) return Corrupt(".pdag declares " + std::to_string(count) + " sections");
  const size_t table_end = kHeaderSize + kEntrySize * count;
  if (bytes.size() < table_end) return Truncated(".pdag ends inside its section table");
  if (HeaderCrc(bytes.first(table_end)) != header_crc) return Corrupt(".pdag header CRC mismatch");
  if (total != bytes.size()) {
    return Truncated(".pdag header says the file has " + std::to_string(total) + " bytes, it has " +
                     std::to_string(bytes.size()));
  }

  PdagFile file;
  bool have_meta = false, have_geometry = false;
  for (uint32_t i = 0; i < count; ++i) {
    const uint8_t* e = bytes.data() + kHeaderSize + kEntrySize * i;
    const std::string tag = TagString(e);
    const auto offset = LoadLE<uint64_t>(e + 8);
    const auto length = LoadLE<uint64_t>(e + 16);
    const auto crc = LoadLE<uint32_t>(e + 24);
    if (offset < table_end || offset > bytes.size() || length > bytes.size() - offset) {
      return Truncated(".pdag section '" + tag + "' lies outside the file");
    }
    const auto data = bytes.subspan(offset, length);
    if (Crc32c(data) != crc) return Corrupt(".pdag section '" + tag + "' fails its CRC32C check");
    if ((tag == "meta" && have_meta) || (tag == "geometry" && have_geometry) ||
        (tag == "colors" && !file.colors.empty())) {
      return Corrupt(".pdag holds section '" + tag + "' twice");
    }
    if (tag == "meta") {
      // Bounded nesting: metadata nested 300,000 deep would overflow the stack in nlohmann's parser.
      auto meta = ParseJson(std::string_view(reinterpret_cast<const char*>(data.data()), data.size()));
      if (!meta.ok()) return Corrupt(".pdag metadata is not valid JSON: " + meta.status().message());
      if (!meta->is_object()) return Corrupt(".pdag metadata is not a JSON object");
      file.meta = std::move(*meta);
      have_meta = true;
    } else if (tag == "geometry") {
      file.geometry.assign(data.begin(), data.end());
      have_geometry = true;
    } else if (tag == "colors") {
      file.colors.assign(data.begin(), data.end());
    }  // unknown sections are skipped: later minor versions may add some
  }
  if (!have_meta || !have_geometry) return Corrupt(".pdag lacks its meta or geometry section");
  return file;
}

StatusOr<std::vector<uint8_t>> ReadFileBytes(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return IoError("cannot open " + path.string() + ": " + std::strerror(errno));
  std::vector<uint8_t> bytes;
  uint8_t chunk[1 << 16];
  for (size_t n; (n = std::fread(chunk, 1, sizeof(chunk), f)) > 0;) bytes.insert(bytes.end(), chunk, chunk + n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return IoError("cannot read " + path.string());
  return bytes;
}

Status WriteFileAtomically(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
  std::string tmp = path.string() + ".tmp-XXXXXX";
  const int fd = mkstemp(tmp.data());
  if (fd < 0) return IoError("cannot create a temporary file beside " + path.string() + ": " + std::strerror(errno));
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string why = std::strerror(errno);
      ::close(fd);
      std::remove(tmp.c_str());
      return IoError("cannot write " + path.string() + ": " + why);
    }
    done += static_cast<size_t>(n);
  }
  if (::fchmod(fd, 0644) != 0 || ::fsync(fd) != 0 || ::close(fd) != 0) {
    std::remove(tmp.c_str());
    return IoError("cannot flush " + path.string());
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return IoError("cannot rename the finished file onto " + path.string() + ": " + std::strerror(errno));
  }
  return Status::Ok();
}

Status WritePdag(const std::filesystem::path& path, const PdagFile& file) {
  return WriteFileAtomically(path, SerializePdag(file));
}

StatusOr<PdagFile> ReadPdag(const std::filesystem::path& path) {
  ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, ReadFileBytes(path));
  return ParsePdag(bytes);
}

}  // namespace pointdag
