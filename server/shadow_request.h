// What POST /v1/datasets/{id}/shadows asks for (proto/PROTOCOL.md §3.2), checked against the
// dataset it is for, and turned into the lights the job casts.
//
// Contract: the body is one of {"direction": [x, y, z]} (the way the light travels, in the dataset's
// axes, z up), {"time": ISO} (the sun at that time), or {"time": ISO, "until": ISO, "samples": N}
// (sun hours: N times evenly from time to until, 1 <= N <= 1440); each may add "bias": B, the
// lights' self-shadow bias in voxels (light.h; 0..16, default 0). Anything else — other members,
// wrong types, NaN-free but zero-length directions, a time without a zone, until before time, a
// time on a dataset that is not georeferenced — is kInvalidArgument with a message for the client.
// The POST plans once to refuse early; the job plans again from the stored request (same answer).
#pragma once

#include <vector>

#include <nlohmann/json.hpp>

#include "pointdag/shadow/light.h"
#include "pointdag/shadow/shadow_layer.h"
#include "pointdag/status.h"

namespace pointdag::server {

struct ShadowPlan {
  ShadowKind kind = ShadowKind::kDirection;
  std::vector<Light> lights;   // one per sample
  nlohmann::json request;      // the body as checked: what the job stores and plans from again
  nlohmann::json description;  // the summary's light members: kind, samples, bias, direction | time, until, hours, sun
};

StatusOr<ShadowPlan> PlanShadows(const nlohmann::json& request, const nlohmann::json& dataset_meta);

}  // namespace pointdag::server
