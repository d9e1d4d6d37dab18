// What a rendering method provides to the tile renderer: radiance along a camera ray.
#pragma once

#include <optional>

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
    // The illuminance AOV (lf/core/aov.h): an estimate of the irradiance (W m^-2, RGB) arriving
    // on the side of `ray`'s first hit the ray sees, 0 for a miss; nullopt for a method that
    // has none (the job's checks refuse the AOV for it first). `sampler` is a stream of its own,
    // so the image's numbers stay those of a render without the AOV.
    virtual std::optional<Rgb> Irradiance(const Ray& ray, Sampler& sampler,
                                          RenderStats& stats) const {
        return std::nullopt;
    }
};

}  // namespace lf
