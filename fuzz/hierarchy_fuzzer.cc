// What a server answers `pointdag fetch`: a hierarchy page and a dataset description, parsed as
// the client does before it trusts a number of them.
#include <cstdint>
#include <string_view>

#include "client.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view body(reinterpret_cast<const char*>(data), size);
  (void)pointdag::client::ParseHierarchyPage(body, 21);
  (void)pointdag::client::ParseDatasetShape(body);
  return 0;
}
