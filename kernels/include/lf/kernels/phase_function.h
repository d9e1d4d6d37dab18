// The Henyey-Greenstein phase function, the one phase function of lightfarm's media, written in
// the cosine of the scattering angle: the angle between a ray's direction of travel before and
// after it scatters (cos 1: straight on). Its mean cosine is g; g > 0 scatters forward.
#pragma once

#include "lf/core/vec.h"

namespace lf {

// Density per steradian: (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^(3/2)), g in (-1, 1).
float HenyeyGreenstein(float cos_theta, float g);

struct PhaseSample {
    Vec3 wi;         // unit: the new direction of travel
    float pdf = 0;   // equals the phase function's value (sampled exactly)
};

// A new direction of travel for a ray travelling along unit `d`, drawn from the phase function
// with u in [0, 1)^2.
PhaseSample SampleHenyeyGreenstein(const Vec3& d, float g, const Vec2& u);

}  // namespace lf
