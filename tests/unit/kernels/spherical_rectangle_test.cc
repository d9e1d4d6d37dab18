#include "lf/kernels/spherical_rectangle.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "chi_square.h"
#include "lf/core/sampler.h"
#include "lf/kernels/spherical_triangle.h"

namespace lf {
namespace {

struct RectangleCase {
    std::string name;
    Vec3 p, corner, ex, ey;
};

// Seen from above and from below its plane, close (nearly a hemisphere), far, off to the side
// at a grazing angle, tilted.
std::vector<RectangleCase> Cases() {
    return {
        {"Above", {0.3f, 0.2f, 1}, {0, 0, 0}, {1, 0, 0}, {0, 2, 0}},
        {"Below", {0.3f, 0.2f, -0.5f}, {0, 0, 0}, {1, 0, 0}, {0, 2, 0}},
        {"Close", {0.5f, 1, 0.05f}, {0, 0, 0}, {1, 0, 0}, {0, 2, 0}},
        {"Far", {0.1f, 0.1f, 8}, {0, 0, 0}, {0.3f, 0, 0}, {0, 0.2f, 0}},
        {"Grazing", {3, 0.5f, 0.2f}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}},
        {"Tilted", {0.2f, -0.4f, 0.9f}, {-0.5f, 0, 0.1f}, {0.6f, 0.6f, 0}, {-0.4f, 0.4f, 0.5f}},
    };
}

// The solid angle of the part (s, t) in [s0, s1] x [t0, t1] of the rectangle: two triangles.
double PartSolidAngle(const RectangleCase& c, double s0, double s1, double t0, double t1) {
    const auto at = [&](double s, double t) {
        return c.corner + c.ex * float(s) + c.ey * float(t);
    };
    return double(TriangleSolidAngle(c.p, at(s0, t0), at(s1, t0), at(s1, t1))) +
           TriangleSolidAngle(c.p, at(s0, t0), at(s1, t1), at(s0, t1));
}

class SphericalRectangleTest : public ::testing::TestWithParam<RectangleCase> {};

TEST_P(SphericalRectangleTest, SolidAngleIsTheTwoTrianglesAndPdfItsInverse) {
    const RectangleCase& c = GetParam();
    const SphericalRectangle sr(c.p, RectangleFrame(c.corner, c.ex, c.ey));
    ASSERT_TRUE(sr.samplable());
    const double expected = PartSolidAngle(c, 0, 1, 0, 1);
    // Float: the four angles near pi / 2 each round to about 1e-7.
    EXPECT_NEAR(sr.solid_angle(), expected, 1e-4 * expected + 2e-6);
    EXPECT_FLOAT_EQ(sr.Pdf(), 1 / sr.solid_angle());
}

// Chi-square of 200,000 samples binned on an 8 x 8 grid of the rectangle against each cell's
// share of the solid angle: uniform in solid angle. Every sample lies on the rectangle, its
// direction towards it, and Invert takes it back to its u.
TEST_P(SphericalRectangleTest, UniformInSolidAngleAndInvertible) {
    const RectangleCase& c = GetParam();
    const SphericalRectangle sr(c.p, RectangleFrame(c.corner, c.ex, c.ey));
    ASSERT_TRUE(sr.samplable());
    constexpr int kGrid = 8, kSamples = 200'000;
    std::vector<double> observed(kGrid * kGrid, 0), expected(kGrid * kGrid, 0);
    for (int i = 0; i < kGrid; ++i) {
        for (int j = 0; j < kGrid; ++j) {
            expected[size_t(i * kGrid + j)] =
                kSamples *
                PartSolidAngle(c, double(i) / kGrid, double(i + 1) / kGrid, double(j) / kGrid,
                               double(j + 1) / kGrid) /
                sr.solid_angle();
        }
    }
    float max_invert_error = 0;
    for (int k = 0; k < kSamples; ++k) {
        Sampler sampler(7, 0, 0, uint64_t(k), SamplerType::kIndependent);
        const Vec2 u = sampler.Get2D();
        const SphericalRectangleSample s = sr.Sample(u);
        ASSERT_GE(s.uv.x, 0);
        ASSERT_LE(s.uv.x, 1);
        ASSERT_GE(s.uv.y, 0);
        ASSERT_LE(s.uv.y, 1);
        const Vec3 on = c.corner + c.ex * s.uv.x + c.ey * s.uv.y;
        ASSERT_LT(Length(s.point - on), 1e-5f * Length(c.ex + c.ey));
        ASSERT_GT(Dot(s.wi, Normalize(s.point - c.p)), 1 - 1e-6f);
        EXPECT_EQ(s.pdf, sr.Pdf());
        const int i = std::min(int(s.uv.x * kGrid), kGrid - 1);
        const int j = std::min(int(s.uv.y * kGrid), kGrid - 1);
        observed[size_t(i * kGrid + j)] += 1;
        const Vec2 back = sr.Invert(s.point);
        max_invert_error =
            std::max({max_invert_error, std::abs(back.x - u.x), std::abs(back.y - u.y)});
    }
    testing::ExpectCountsMatch(observed, expected, c.name, int(Cases().size()));
    // float: the angle sums lose about 1e-6 of their ~pi, relative to the solid angle.
    EXPECT_LT(max_invert_error, 2e-6f / sr.solid_angle() + 1e-4f) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Rectangles, SphericalRectangleTest, ::testing::ValuesIn(Cases()),
                         [](const auto& info) { return info.param.name; });

TEST(SphericalRectangle, NotSamplableInItsPlaneFarAwayOrBelowTheMinimum) {
    const Vec3 corner(0, 0, 0), ex(1, 0, 0), ey(0, 1, 0);
    const RectangleFrame frame(corner, ex, ey);
    EXPECT_FALSE(SphericalRectangle({2, 0.5f, 0}, frame).samplable());
    EXPECT_FALSE(SphericalRectangle({0.5f, 0.5f, 0}, frame).samplable());
    EXPECT_EQ(SphericalRectangle({0.5f, 0.5f, 0}, frame).Pdf(), 0);
    EXPECT_FALSE(SphericalRectangle({0.5f, 0.5f, 500}, frame).samplable());
    // 1 / 25 sr from 5 above: samplable unless the caller asks for more.
    EXPECT_TRUE(SphericalRectangle({0.5f, 0.5f, 5}, frame).samplable());
    EXPECT_FALSE(SphericalRectangle({0.5f, 0.5f, 5}, frame, 0.25f).samplable());
    EXPECT_TRUE(SphericalRectangle({0.5f, 0.5f, 1}, frame, 0.25f).samplable());
    // The bound that skips the trigonometry never rejects what the exact test would take:
    // points along the axis where the solid angle crosses the threshold.
    for (float z = 0.5f; z < 4; z *= 1.01f) {
        const Vec3 p(0.3f, 0.6f, z);
        const double omega = PartSolidAngle({"", p, corner, ex, ey}, 0, 1, 0, 1);
        if (std::abs(omega / 0.25 - 1) < 1e-4) continue;
        EXPECT_EQ(SphericalRectangle(p, frame, 0.25f).samplable(), omega >= 0.25) << z;
    }
}

}  // namespace
}  // namespace lf
