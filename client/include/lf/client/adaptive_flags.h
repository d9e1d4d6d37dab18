// The adaptive sampling options `render`, `submit` and `plan` share.
#pragma once

#include <CLI/CLI.hpp>

#include "lf/job/adaptive_plan.h"

namespace lf {

void AddAdaptiveFlags(CLI::App* cmd, AdaptiveSettings& settings);
// After parsing: with --noise-threshold and no --spp, `spp` (the minimum samples per pixel)
// becomes Cycles' automatic minimum for the threshold (lf::NoiseThresholdMinSpp).
void ApplyNoiseThresholdMinSpp(const CLI::App& cmd, const AdaptiveSettings& settings,
                               uint64_t& spp);

}  // namespace lf
