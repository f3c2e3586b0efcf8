// `pointdag bench --shadow DIR` (issue #16): the light-space shadow DAG on every scan of DIR at two
// resolutions (grid depth 8 and 10; POINTDAG_SHADOW_DEPTHS=8,10,12 chooses others), one sun-like
// light: sizes against the dense grid and a plain shadow map, what each relaxation step of the
// undefined cells gains, build time and memory, queries per second; the free-space mode's size, build
// time and memory up to depth 10; then the exact per-voxel shadows' speed.
#pragma once

#include <filesystem>
#include <ostream>

namespace pointdag {

// Writes a Markdown table to `out`; 0 when every scan was measured, 1 otherwise.
int RunShadowBench(const std::filesystem::path& data_dir, std::ostream& out);
// The exact per-voxel shadows on 1 and 2 threads and 24 suns' sun hours (exact_shadow_bench.cc); RunShadowBench
// ends with it.
int RunExactShadowBench(const std::filesystem::path& data_dir, std::ostream& out);

}  // namespace pointdag
