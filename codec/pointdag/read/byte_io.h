// Little-endian loads and stores on byte buffers; memcpy keeps them free of alignment traps.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace pointdag {

template <typename T>
T LoadLE(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));  // x86-64 and arm64 are little-endian; Debian's big-endian ports are not targets
  return v;
}

template <typename T>
void AppendLE(std::vector<unsigned char>& out, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}

// A NUL-padded fixed-width text field (LAS user ids, system identifiers).
inline std::string FixedString(const unsigned char* p, size_t n) {
  size_t len = 0;
  while (len < n && p[len] != 0) ++len;
  return std::string(reinterpret_cast<const char*>(p), len);
}

}  // namespace pointdag
