// report.html: the nightly report for people. One self-contained page (inline CSS and SVG, no
// scripts): the run's provenance, a summary table, per case a rate-distortion plot (bits per point
// against PSNR-Y: VBR, fixed3, hierarchical and the best image mapping, with our lossless and Draco's lossless
// totals as lines) and the trend of its bits per point across `history` (older reports, oldest first).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace pointdag {

std::string ReportHtml(const nlohmann::json& report, const std::vector<nlohmann::json>& history);

}  // namespace pointdag
