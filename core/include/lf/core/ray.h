#pragma once

#include <limits>

#include "lf/core/vec.h"

namespace lf {

struct Ray {
    Vec3 o;
    Vec3 d;
    float t_max = std::numeric_limits<float>::infinity();
};

}  // namespace lf
