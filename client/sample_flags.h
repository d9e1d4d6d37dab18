// --clamp and --aov: what each sample contributes beyond its radiance, for the commands that
// render an image (`render`, `submit`; `plan` takes --clamp, which changes the noise it costs).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>

namespace lf {

// --clamp L into `clamp` (>= 0; 0 = off).
void AddClampFlag(CLI::App* cmd, double& clamp);

// --clamp, and --aov LIST into `aovs` (lf/core/aov.h flags).
void AddSampleFlags(CLI::App* cmd, double& clamp, uint32_t& aovs);

}  // namespace lf
