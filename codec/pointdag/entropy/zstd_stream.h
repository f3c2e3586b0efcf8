// Decompressing a zstd frame from outside: streamed, growing the output only as real data comes
// out, and stopping at a limit the caller derives from counts it has already validated. A frame's
// own content-size field is never trusted, and a frame of a few KB that expands to gigabytes (zstd
// reaches ~32000:1 on runs) stops at the limit instead of at the end of memory.
#pragma once

#include <zstd.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "pointdag/status.h"

namespace pointdag {

// Appends the frame's content to `out`; `what` names the stream in messages ("geometry stream").
inline Status DecompressBounded(std::span<const uint8_t> frame, uint64_t limit, std::vector<uint8_t>& out,
                                const std::string& what) {
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!ctx) return ResourceLimit("cannot allocate a zstd decoder");
  ZSTD_inBuffer in = {frame.data(), frame.size(), 0};
  std::vector<uint8_t> chunk(ZSTD_DStreamOutSize());
  const size_t start = out.size();
  size_t last = 1;
  while (in.pos < in.size || last != 0) {
    ZSTD_outBuffer o = {chunk.data(), chunk.size(), 0};
    last = ZSTD_decompressStream(ctx.get(), &o, &in);
    if (ZSTD_isError(last)) return Corrupt(what + " fails to decompress: " + ZSTD_getErrorName(last));
    if (out.size() - start + o.pos > limit) {
      return Corrupt(what + " decompresses to more than the " + std::to_string(limit) + " bytes its counts allow");
    }
    out.insert(out.end(), chunk.data(), chunk.data() + o.pos);
    if (o.pos == 0 && in.pos == in.size && last != 0) return Truncated(what + "'s zstd frame is cut short");
  }
  return Status::Ok();
}

}  // namespace pointdag
