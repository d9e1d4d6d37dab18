// What a rendering method provides to the tile renderer: radiance along a camera ray.
#pragma once

#include "lf/core/film.h"
#include "lf/core/ray.h"
#include "lf/core/rgb.h"
#include "lf/core/sampler.h"

namespace lf {

class EmbreeScene;

class RadianceEstimator {
  public:
    virtual ~RadianceEstimator() = default;
    // An estimate of L along `ray`; counts the rays it casts in stats.rays.
    virtual Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const = 0;
    // The scene it traces: where the tile renderer reads the first-hit AOVs.
    virtual const EmbreeScene& geometry() const = 0;
};

}  // namespace lf
