// `lightfarm bench`: path tracing throughput against Embree's raw ray rate on one scene.
#pragma once

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "lf/core/scene_loader.h"
#include "lf/job/settings.h"

namespace lf {

struct BenchOptions {
    std::string scene_path;
    uint64_t spp = defaults::kSpp;
    int threads = 2;
    SceneOptions scene{.width = 256, .height = 256};
    int max_depth = defaults::kMaxDepth;
    SamplerType sampler = defaults::kSampler;
    LightStrategy light_strategy = defaults::kLightStrategy;
    uint64_t raw_rays = 4'000'000;
};

absl::Status RunBench(const BenchOptions& options);

}  // namespace lf
