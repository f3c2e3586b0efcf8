// PROJ, loaded on first use rather than linked.
//
// libproj brings in 35 more shared libraries (sqlite3, libtiff, libcurl-gnutls and through it
// gnutls, krb5, ldap, ssh2, libcrypto, ...). Linked, their ~13,000 symbol relocations cost every
// start of the CLI and the daemon about 29 M instructions (~7 ms) in the dynamic loader, while only
// georeferencing (georeference.cc) calls PROJ. So the library is opened by its SONAME when a scan is
// first georeferenced, and the proj_* functions georeference.cc calls are looked up in one table.
// proj.h still gives the types and the functions' signatures.
#pragma once

#include <proj.h>

#include "pointdag/status.h"

namespace pointdag {

// The proj_* functions georeference.cc calls: X(name) stands for proj_<name>.
#define POINTDAG_PROJ_FUNCTIONS(X)                                                                                \
  X(context_create) X(context_destroy) X(context_set_enable_network) X(log_level) X(context_errno)                \
  X(context_errno_string) X(create) X(create_crs_to_crs_from_pj) X(normalize_for_visualization) X(clone)          \
  X(destroy) X(is_crs) X(get_type) X(get_name) X(get_id_auth_name) X(get_id_code) X(as_wkt) X(get_source_crs)     \
  X(crs_get_sub_crs) X(crs_get_coordinate_system) X(cs_get_axis_count) X(cs_get_axis_info) X(trans_generic)

struct ProjApi {
#define POINTDAG_PROJ_MEMBER(name) decltype(&::proj_##name) name = nullptr;
  POINTDAG_PROJ_FUNCTIONS(POINTDAG_PROJ_MEMBER)
#undef POINTDAG_PROJ_MEMBER
};

// Opens PROJ once per process (thread-safe; never closed); kUnsupported saying why when it cannot.
Status LoadProj();

// The table, once LoadProj() has succeeded.
const ProjApi& Proj();

}  // namespace pointdag
