// --sampler, --light-sampling, --clamp and --aov: where each sample's random numbers come from,
// how its paths sample lights, and what it contributes beyond its radiance, for the commands
// that render an image (`render`, `submit`; `plan`, `bench` and `converge` take --sampler and
// --light-sampling, and `plan` --clamp, which change the noise and so what a render costs).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>

#include "lf/core/light_strategy.h"
#include "lf/core/sampler.h"

namespace lf {

// --sampler independent|sobol into `sampler`; its default is what `sampler` holds.
void AddSamplerFlag(CLI::App* cmd, SamplerType& sampler);

// --light-sampling power|bvh into `strategy`; its default is what `strategy` holds.
void AddLightSamplingFlag(CLI::App* cmd, LightStrategy& strategy);

// --clamp L into `clamp` (>= 0; 0 = off).
void AddClampFlag(CLI::App* cmd, double& clamp);

// --sampler, --light-sampling, --clamp, and --aov LIST into `aovs` (lf/core/aov.h flags).
void AddSampleFlags(CLI::App* cmd, SamplerType& sampler, LightStrategy& light_strategy,
                    double& clamp, uint32_t& aovs);

}  // namespace lf
