// Affine maps of 3D space, x -> M x + t: scene and glTF node transforms.
#pragma once

#include <array>

#include "lf/core/vec.h"

namespace lf {

// Rows of a 3x4 matrix: M its 3x3 part, t its last column.
struct Affine {
    std::array<std::array<double, 4>, 3> m{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};

    Vec3d Apply(const Vec3d& p) const { return ApplyLinear(p) + Vec3d(m[0][3], m[1][3], m[2][3]); }
    Vec3d ApplyLinear(const Vec3d& v) const {
        return {Dot(Row(0), v), Dot(Row(1), v), Dot(Row(2), v)};
    }
    // This transform followed by `next`.
    Affine Then(const Affine& next) const;
    Vec3d Row(int r) const { return {m[r][0], m[r][1], m[r][2]}; }
    double Determinant() const { return Dot(Row(0), Cross(Row(1), Row(2))); }
    // Where normals go: the cofactor matrix of M (det(M) M^-T) times det's sign, which
    // normalising scales to M^-T's direction while a mirror still flips the normal with the
    // front face.
    Affine NormalMatrix() const;
    bool IsFinite() const;
    // The map back, x -> M^-1 (x - t); M must be invertible (a singular M gives non-finite
    // entries).
    Affine Inverse() const;

    // translation * rotation * scale, glTF's node transform; `rotation` a unit quaternion
    // (x, y, z, w).
    static Affine FromTrs(const Vec3d& translation, const std::array<double, 4>& rotation,
                          const Vec3d& scale);
};

}  // namespace lf
