// The scene's environment light (a sky at infinity) as the path tracer sees it: the radiance
// arriving along a direction, and directions sampled towards it. A uniform sky samples the
// sphere uniformly; a latitude-longitude map is importance sampled by luminance times
// sin(theta) through a piecewise-constant 2D distribution over its texels. Le reads the nearest
// texel, so it is constant on exactly the pieces the distribution is: a sample's Le / pdf is
// one texel's value over that texel's density, and Pdf(w) is the density Sample draws w with.
#pragma once

#include <optional>

#include "lf/core/piecewise_distribution.h"
#include "lf/core/scene.h"

namespace lf {

class EnvironmentEmitter {
  public:
    explicit EnvironmentEmitter(const EnvironmentLight& light);

    struct DirectionSample {
        Vec3 wi;       // unit, towards the sky
        Rgb radiance;  // arriving along -wi
        float pdf;     // per solid angle
    };

    // Radiance arriving from direction w (unit, from the receiver towards the sky).
    Rgb Le(const Vec3& w) const;
    std::optional<DirectionSample> Sample(const Vec2& u) const;
    // Density per solid angle with which Sample returns w.
    float Pdf(const Vec3& w) const;
    // The radiance averaged over the sphere of directions: the light's power per unit of
    // pi * area * pi it falls on.
    const Rgb& MeanRadiance() const { return mean_; }

  private:
    // The map's texel at (u, v) times the light's radiance; `radiance` alone without a map.
    Rgb MapValue(const Vec2& uv) const;
    // The map's (u, v) for a world direction, after turning it by +rotate_y about +y.
    Vec2 MapUv(const Vec3& w) const;

    EnvironmentLight light_;
    float cos_rotation_, sin_rotation_;
    std::optional<PiecewiseConstant2D> distribution_;  // with a map
    Rgb mean_;
};

}  // namespace lf
