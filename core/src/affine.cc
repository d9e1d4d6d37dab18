#include "lf/core/affine.h"

#include <cmath>

namespace lf {

Affine Affine::Then(const Affine& next) const {
    Affine out;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) {
            out.m[r][c] = next.m[r][0] * m[0][c] + next.m[r][1] * m[1][c] + next.m[r][2] * m[2][c] +
                          (c == 3 ? next.m[r][3] : 0);
        }
    }
    return out;
}

Affine Affine::NormalMatrix() const {
    const double sign = Determinant() < 0 ? -1 : 1;
    const Vec3d cofactor[3] = {Cross(Row(1), Row(2)), Cross(Row(2), Row(0)), Cross(Row(0), Row(1))};
    // M^-1's columns are these over det(M), so they are the rows of det(M) M^-T.
    Affine n;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) n.m[r][c] = sign * cofactor[r][c];
        n.m[r][3] = 0;
    }
    return n;
}

Affine Affine::Inverse() const {
    // M^-1 is the transposed cofactor matrix over det(M); t goes to -M^-1 t.
    const double det = Determinant();
    const Vec3d cofactor[3] = {Cross(Row(1), Row(2)), Cross(Row(2), Row(0)), Cross(Row(0), Row(1))};
    Affine inverse;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) inverse.m[r][c] = cofactor[c][r] / det;
    }
    const Vec3d t = inverse.ApplyLinear(Vec3d(m[0][3], m[1][3], m[2][3]));
    for (int r = 0; r < 3; ++r) inverse.m[r][3] = -t[r];
    return inverse;
}

bool Affine::IsFinite() const {
    for (const auto& row : m) {
        for (const double v : row) {
            if (!std::isfinite(v)) return false;
        }
    }
    return true;
}

Affine Affine::FromTrs(const Vec3d& translation, const std::array<double, 4>& rotation,
                       const Vec3d& scale) {
    const auto [x, y, z, w] = rotation;
    Affine a;
    a.m = {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), translation.x},
            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), translation.y},
            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), translation.z}}};
    for (int r = 0; r < 3; ++r) {
        a.m[r][0] *= scale.x;
        a.m[r][1] *= scale.y;
        a.m[r][2] *= scale.z;
    }
    return a;
}

}  // namespace lf
