// OpenPclScan (pcl_reader.h): loads libpointdag_pcl_reader.so on first use and calls into it.
#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "pointdag/read/pcl_reader.h"

namespace pointdag {
namespace {

constexpr const char* kModuleName = "libpointdag_pcl_reader.so";

// Where the module may be: the environment's choice alone when there is one; else the build tree
// this binary was built in (tests, scripts/run), then lib/pointdag/ beside the executable's bin/ (an
// installed copy, the container image's /usr/local).
std::vector<std::string> Candidates() {
  if (const char* chosen = std::getenv("POINTDAG_PCL_READER"); chosen && *chosen) return {chosen};
  std::vector<std::string> out;
#ifdef POINTDAG_PCL_READER_BUILT_AT
  out.emplace_back(POINTDAG_PCL_READER_BUILT_AT);
#endif
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) out.push_back((exe.parent_path().parent_path() / "lib" / "pointdag" / kModuleName).string());
  return out;
}

struct Module {
  OpenPclScanFn open = nullptr;
  std::string why_not;  // when `open` is null
};

// Loaded once per process and never unloaded: the readers it makes keep its code.
const Module& LoadedModule() {
  static Module module;
  static std::once_flag once;
  std::call_once(once, [] {
    std::string tried;
    for (const std::string& path : Candidates()) {
      void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!handle) {
        tried += (tried.empty() ? "" : "; ") + std::string(dlerror());
        continue;
      }
      module.open = reinterpret_cast<OpenPclScanFn>(dlsym(handle, kOpenPclScanSymbol));
      if (module.open) return;
      tried += (tried.empty() ? "" : "; ") + path + " has no " + kOpenPclScanSymbol;
    }
    module.why_not = tried;
  });
  return module;
}

}  // namespace

StatusOr<std::unique_ptr<ScanReader>> OpenPclScan(const std::filesystem::path& path, ScanFormat format) {
  const Module& module = LoadedModule();
  if (!module.open) {
    return Unsupported(std::string("this ") + ScanFormatName(format) + " file needs PCL's reader, " + kModuleName +
                       ", which could not be loaded (set POINTDAG_PCL_READER to its path): " + module.why_not);
  }
  StatusOr<std::unique_ptr<ScanReader>> out = Internal("PCL reader module returned nothing");
  module.open(path.c_str(), format, &out);
  return out;
}

}  // namespace pointdag
