#pragma once

#include <limits>

#include "lf/core/vec.h"

namespace lf {

struct Ray {
    Vec3 o;
    Vec3 d;
    float t_max = std::numeric_limits<float>::infinity();
    // When in the shutter the ray travels: 0 at its opening, 1 at its closing (Embree's time).
    // Geometry and cameras that do not move ignore it.
    float time = 0;
};

}  // namespace lf
