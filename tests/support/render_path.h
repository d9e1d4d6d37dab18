// Path tracing a scene built in a test through local mode's executor, with the estimator
// `--method path` takes for it (VolPathTracer for scenes with media).
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "lf/core/camera.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"
#include "lf/local/method_factory.h"

namespace lf::testing {

struct PathRender {
    RenderOutput out;
    std::unique_ptr<EmbreeScene> embree;  // for tests that cast rays of their own
};

inline PathRender RenderPath(const Scene& scene, uint64_t spp, int max_depth = -1,
                             uint64_t seed = 1, SamplerType sampler = defaults::kSampler,
                             LightStrategy strategy = LightStrategy::kBvh) {
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    const Camera camera(scene.camera, (*es)->origin());
    const std::unique_ptr<RadianceEstimator> tracer =
        MakeRayTracer(Method::kPath, **es, max_depth, strategy).value();
    RenderSettings settings;
    settings.spp = spp;
    settings.seed = seed;
    settings.tile = 8;
    settings.sampler = sampler;
    return {RenderImage(camera, *tracer, settings).value(), std::move(*es)};
}

}  // namespace lf::testing
