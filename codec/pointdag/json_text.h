// JSON text that crosses a trust boundary: parsed with a nesting bound, written without throwing.
//
// Contract: DumpJson() never throws — strings holding invalid UTF-8 (a LAS GeoKey ASCII record, a
// query parameter) are written with U+FFFD in place of each bad byte, so a hostile string can
// neither abort a job nor drop a connection. ParseJson() refuses text nested deeper than
// `max_depth` before nlohmann sees it (deep nesting overflows the stack in recursive code paths),
// and returns kMalformed for anything that is not JSON; it never throws either.
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "pointdag/status.h"

namespace pointdag {

constexpr size_t kMaxJsonDepth = 64;

std::string DumpJson(const nlohmann::json& value, int indent = -1);
StatusOr<nlohmann::json> ParseJson(std::string_view text, size_t max_depth = kMaxJsonDepth);

}  // namespace pointdag
