// TOML text as an operator (or whoever can write the config file) gives it: the daemon's config
// loader, with its type and range checks.
#include <cstdint>
#include <string_view>

#include "config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pointdag::server::DaemonConfig config;
  (void)pointdag::server::ParseConfigText(std::string_view(reinterpret_cast<const char*>(data), size), config);
  return 0;
}
