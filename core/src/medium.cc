#include "lf/core/medium.h"

#include <cmath>

namespace lf {

float VolumeGrid::Lookup(const Vec3d& q) const {
    const double fx = std::floor(q.x), fy = std::floor(q.y), fz = std::floor(q.z);
    // Far outside the lattice (or NaN) the cast below would overflow: everything there reads
    // the background.
    constexpr double kFar = 1 << 30;
    if (!(std::abs(fx) < kFar && std::abs(fy) < kFar && std::abs(fz) < kFar)) return background;
    const int x = int(fx), y = int(fy), z = int(fz);
    const float dx = float(q.x - fx), dy = float(q.y - fy), dz = float(q.z - fz);
    const auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
    const auto plane = [&](int zz) {
        return lerp(lerp(At(x, y, zz), At(x + 1, y, zz), dx),
                    lerp(At(x, y + 1, zz), At(x + 1, y + 1, zz), dx), dy);
    };
    return lerp(plane(z), plane(z + 1), dz);
}

}  // namespace lf
