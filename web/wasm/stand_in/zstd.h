// Stand-in for <zstd.h> in the WebAssembly decoder build: Debian packages no zstd for emscripten.
// It declares what codec/pointdag uses and makes every call fail. The entry (decode_tile_wasm.cc)
// refuses zstd-coded geometry and lossless colors before decoding, so no tile reaches these.
#pragma once

#include <stddef.h>

typedef struct ZSTD_DCtx_s ZSTD_DCtx;
typedef struct {
  const void* src;
  size_t size;
  size_t pos;
} ZSTD_inBuffer;
typedef struct {
  void* dst;
  size_t size;
  size_t pos;
} ZSTD_outBuffer;

#define ZSTD_CONTENTSIZE_ERROR (0ULL - 2)

inline constexpr size_t kZstdStandInError = static_cast<size_t>(-1);

inline unsigned ZSTD_isError(size_t code) { return code == kZstdStandInError; }
inline const char* ZSTD_getErrorName(size_t) { return "zstd is not in the WebAssembly build"; }
inline size_t ZSTD_compressBound(size_t) { return 0; }
inline size_t ZSTD_compress(void*, size_t, const void*, size_t, int) { return kZstdStandInError; }
inline ZSTD_DCtx* ZSTD_createDCtx() { return nullptr; }
inline size_t ZSTD_freeDCtx(ZSTD_DCtx*) { return 0; }
inline size_t ZSTD_DStreamOutSize() { return 1; }
inline size_t ZSTD_decompressStream(ZSTD_DCtx*, ZSTD_outBuffer*, ZSTD_inBuffer*) { return kZstdStandInError; }
inline unsigned long long ZSTD_getFrameContentSize(const void*, size_t) { return ZSTD_CONTENTSIZE_ERROR; }
