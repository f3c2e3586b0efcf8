#include "pointdag/georef/proj_library.h"

#include <dlfcn.h>

#include <string>

namespace pointdag {
namespace {

struct Loaded {
  ProjApi api;
  std::string why_not;  // empty when every function was found
};

// The SONAME the build linked against, through the usual library search; then the directory the
// build found it in, for a PROJ outside that search (the executable has no rpath to it any more).
Loaded Load() {
  Loaded out;
  void* handle = nullptr;
  for (const char* path : {POINTDAG_PROJ_SONAME, POINTDAG_PROJ_DIR "/" POINTDAG_PROJ_SONAME}) {
    if ((handle = dlopen(path, RTLD_LAZY | RTLD_LOCAL))) break;
    out.why_not += std::string(out.why_not.empty() ? "" : "; ") + dlerror();
  }
  if (!handle) return out;
  out.why_not.clear();
#define POINTDAG_PROJ_RESOLVE(name)                                                                  \
  out.api.name = reinterpret_cast<decltype(out.api.name)>(dlsym(handle, "proj_" #name));             \
  if (!out.api.name) out.why_not += std::string(out.why_not.empty() ? "" : ", ") + "proj_" #name;
  POINTDAG_PROJ_FUNCTIONS(POINTDAG_PROJ_RESOLVE)
#undef POINTDAG_PROJ_RESOLVE
  if (!out.why_not.empty()) out.why_not = POINTDAG_PROJ_SONAME " lacks " + out.why_not;
  return out;
}

const Loaded& Library() {
  static const Loaded loaded = Load();  // a function-local static: initialized once, thread-safe
  return loaded;
}

}  // namespace

Status LoadProj() {
  const std::string& why_not = Library().why_not;
  if (!why_not.empty()) return Unsupported("georeferencing needs PROJ, which could not be loaded: " + why_not);
  return Status::Ok();
}

const ProjApi& Proj() { return Library().api; }

}  // namespace pointdag
