// Unidirectional path tracing of the full rendering equation: next-event estimation with
// multiple importance sampling (power heuristic) for area lights, next-event estimation for
// point lights, BSDF sampling at every vertex and Russian roulette on the path throughput.
#pragma once

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/radiance.h"

namespace lf {

class PathTracer : public RadianceEstimator {
public:
    // max_depth: the most bounces a path may take; negative means unlimited (roulette only).
    PathTracer(const EmbreeScene& scene, int max_depth);

    Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const override;

private:
    const EmbreeScene& scene_;
    LightSampler lights_;
    int max_depth_;
};

}  // namespace lf
