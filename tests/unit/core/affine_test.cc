#include "lf/core/affine.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lf {
namespace {

Affine Skewed(double mirror) {
    Affine a;
    a.m = {{{2 * mirror, 0.5, 0, 1}, {0, 1, 0.3, -2}, {0.1, 0, 3, 0.5}}};
    return a;
}

// A normal stays perpendicular to every vector in its plane after both are mapped, and keeps
// its side of the mapped front face (the cross product of the mapped edges) under a mirror.
TEST(Affine, NormalsStayPerpendicularAndOnTheFrontSide) {
    for (const double mirror : {1.0, -1.0}) {
        const Affine a = Skewed(mirror);
        const Vec3d e1(1, 0.2, 0), e2(-0.3, 1, 0.1);
        const Vec3d n = Cross(e1, e2);
        const Vec3d n2 = a.NormalMatrix().ApplyLinear(n);
        const Vec3d f1 = a.ApplyLinear(e1), f2 = a.ApplyLinear(e2);
        EXPECT_NEAR(Dot(n2, f1), 0, 1e-12);
        EXPECT_NEAR(Dot(n2, f2), 0, 1e-12);
        // The mapped triangle's front (its winding flipped by a mirror, as the loaders do).
        const Vec3d front = mirror > 0 ? Cross(f1, f2) : Cross(f2, f1);
        EXPECT_GT(Dot(n2, front), 0) << mirror;
    }
}

TEST(Affine, ThenAppliesThisFirst) {
    Affine scale, move;
    scale.m[0][0] = scale.m[1][1] = scale.m[2][2] = 2;
    move.m[0][3] = 1;
    const Vec3d p(1, 1, 1);
    const Vec3d q = scale.Then(move).Apply(p);
    EXPECT_EQ(q.x, 3);
    EXPECT_EQ(q.y, 2);
    EXPECT_EQ(scale.Then(move).Determinant(), 8);
    EXPECT_TRUE(scale.IsFinite());
    scale.m[1][1] = 1e300 * 1e300;
    EXPECT_FALSE(scale.IsFinite());
}

TEST(Affine, FromTrsScalesThenRotatesThenTranslates) {
    // A quarter turn about +z (x -> y, y -> -x), scale (2, 3, 4), then translate (1, 2, 3);
    // sqrt(0.5) squared is 0.5 within a few ulps.
    const double s = std::sqrt(0.5);
    const Affine a = Affine::FromTrs(Vec3d(1, 2, 3), {0, 0, s, s}, Vec3d(2, 3, 4));
    const Vec3d q = a.Apply(Vec3d(1, 1, 1));
    // Scaled (2, 3, 4), turned (-3, 2, 4), moved (-2, 4, 7).
    EXPECT_NEAR(q.x, -2, 1e-14);
    EXPECT_NEAR(q.y, 4, 1e-14);
    EXPECT_NEAR(q.z, 7, 1e-14);
    EXPECT_NEAR(a.Determinant(), 24, 1e-13);
}

// Inverse undoes the map on both sides, mirrored or not, translation included.
TEST(Affine, InverseUndoesTheMap) {
    for (const double mirror : {1.0, -1.0}) {
        const Affine a = Skewed(mirror);
        const Affine inverse = a.Inverse();
        for (const Vec3d& p : {Vec3d(0, 0, 0), Vec3d(1, -2, 3), Vec3d(-7.5, 0.25, 100)}) {
            const Vec3d there = inverse.Apply(a.Apply(p)), back = a.Apply(inverse.Apply(p));
            for (int i = 0; i < 3; ++i) {
                EXPECT_NEAR(there[i], p[i], 1e-12);
                EXPECT_NEAR(back[i], p[i], 1e-12);
            }
        }
        EXPECT_NEAR(a.Determinant() * inverse.Determinant(), 1, 1e-12);
    }
    Affine flat;
    flat.m[2][2] = 0;
    EXPECT_FALSE(flat.Inverse().IsFinite());
}

}  // namespace
}  // namespace lf
