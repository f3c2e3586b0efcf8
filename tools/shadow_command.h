// `pointdag shadow`: which voxels of a dataset a directional light (or the sun at a time) leaves in
// shadow, built as a shadow DAG (issue #16); sun hours over a span of time from N samples.
//
//   pointdag shadow IN (--direction X,Y,Z | --time ISO8601 [--until ISO8601 --samples N])
//                      (--voxel S | --depth D) [--bias VOXELS] [--json] [-o OUT.ply | -o OUT.pdsh]
//
// Exit codes as the rest of the CLI: 0 ok, 1 bad input (message on stderr), 2 usage.
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace pointdag {

struct ShadowCommand {
  std::string input, output;
  std::optional<std::string> direction, time, until;
  std::optional<int> samples;
  std::optional<double> voxel;
  std::optional<int> depth;
  double bias = 0;  // Light::bias_voxels of every light
  bool json = false;
};

CLI::App* AddShadowCommand(CLI::App& app, ShadowCommand& command);
int RunShadowCommand(const ShadowCommand& command);

}  // namespace pointdag
