#include "lf/kernels/spherical_triangle.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "chi_square.h"
#include "lf/core/sampler.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

using testing::kPi;

struct TriangleCase {
    std::string name;
    Vec3 p, v0, v1, v2;
};

// Large, small, obtuse, seen at grazing angles and nearly filling the hemisphere; all
// samplable (the solid angles are checked below).
std::vector<TriangleCase> Cases() {
    return {
        {"Octant", {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
        {"Large", {0.2f, 0.1f, 0.3f}, {-2, -2, 0}, {3, -1, 0}, {0, 3, 0}},
        {"Small", {0.3f, -0.2f, 2}, {0, 0, 0}, {0.1f, 0, 0.01f}, {0.02f, 0.09f, 0}},
        {"NearThreshold", {0, 0, 3}, {0, 0, 0}, {0.06f, 0, 0}, {0, 0.06f, 0.01f}},
        {"Obtuse", {0, 0, 0}, {-3, 0, -1}, {3, 0, -1}, {0, 0.3f, -1}},
        {"Grazing", {0, 0, 0.02f}, {1, 0, 0}, {2, 0.5f, 0}, {1.5f, -0.7f, 0}},
        {"NearHemisphere", {0.1f, 0.05f, 1.5f}, {-50, -50, 0}, {60, -40, 0}, {0, 70, 0}},
    };
}

// Solid angle as the integral of cos / r^2 over the triangle's area, on the unit square mapped
// onto the triangle by x = v0 + s (e1 + t (e2 - e1)) (Jacobian s |e1 x e2|).
double QuadratureSolidAngle(const TriangleCase& c) {
    const Vec3d p(c.p), v0(c.v0), e1 = Vec3d(c.v1) - v0, e2 = Vec3d(c.v2) - v0;
    const Vec3d cross = Cross(e1, e2);
    const Vec3d n = Normalize(cross);
    const double jacobian = Length(cross);
    const auto f = [&](double s, double t) {
        const Vec3d d = v0 + (e1 + (e2 - e1) * t) * s - p;
        const double r2 = LengthSquared(d);
        return std::abs(Dot(n, d)) / (r2 * std::sqrt(r2)) * s * jacobian;
    };
    constexpr int kPieces = 8;
    double sum = 0;
    for (int i = 0; i < kPieces; ++i) {
        for (int j = 0; j < kPieces; ++j) {
            const double s0 = double(i) / kPieces, s1 = double(i + 1) / kPieces;
            const double t0 = double(j) / kPieces, t1 = double(j + 1) / kPieces;
            sum += testing::Adaptive2D(
                f, s0, s1, t0, t1, testing::GaussLegendre2D(f, s0, s1, t0, t1), 1e-12, 1e-10, 14);
        }
    }
    return sum;
}

TEST(SphericalTriangleTest, SolidAngleMatchesQuadrature) {
    for (const TriangleCase& c : Cases()) {
        const double quadrature = QuadratureSolidAngle(c);
        const float omega = TriangleSolidAngle(c.p, c.v0, c.v1, c.v2);
        std::printf("%-16s solid angle %.7g quadrature %.7g\n", c.name.c_str(), omega, quadrature);
        // Float result of a double computation: a few ulps.
        EXPECT_NEAR(omega, quadrature, 4e-7 * quadrature) << c.name;
        // Either winding, either side.
        EXPECT_EQ(omega, TriangleSolidAngle(c.p, c.v0, c.v2, c.v1)) << c.name;
    }
    EXPECT_NEAR(TriangleSolidAngle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}), kPi / 2, 2e-7);
}

TEST(SphericalTriangleTest, TetrahedronFacesCoverTheSphere) {
    const std::array<Vec3, 4> v = {Vec3(0, 0, 0), Vec3(2, 0.1f, 0), Vec3(0.3f, 1.5f, 0.2f),
                                   Vec3(0.5f, 0.4f, 1.8f)};
    for (int i = 0; i < 200; ++i) {
        Sampler sampler(7, 0, 0, uint64_t(i));
        // A random point inside the tetrahedron, some near its faces and vertices.
        float w[4], sum = 0;
        for (float& x : w) sum += x = std::pow(sampler.Get1D(), 3.0f) + 1e-6f;
        Vec3 p;
        for (int k = 0; k < 4; ++k) p += v[size_t(k)] * (w[k] / sum);
        const double total = double(TriangleSolidAngle(p, v[0], v[1], v[2])) +
                             TriangleSolidAngle(p, v[0], v[1], v[3]) +
                             TriangleSolidAngle(p, v[0], v[2], v[3]) +
                             TriangleSolidAngle(p, v[1], v[2], v[3]);
        EXPECT_NEAR(total, 4 * kPi, 4e-6) << "point " << i;
    }
}

TEST(SphericalTriangleTest, DegenerateAndOutOfRangeAreLeftToAreaSampling) {
    const Vec3 v0(0, 0, 0), v1(1, 0, 0), v2(0, 1, 0);
    const auto expect_not_samplable = [](const SphericalTriangle& st, const char* what) {
        EXPECT_FALSE(st.samplable()) << what;
        EXPECT_EQ(st.Pdf(), 0) << what;
    };
    // In the triangle's plane (edge-on), inside it or beyond an edge.
    EXPECT_EQ(TriangleSolidAngle({2, 3, 0}, v0, v1, v2), 0);
    expect_not_samplable(SphericalTriangle({2, 3, 0}, v0, v1, v2), "edge-on");
    expect_not_samplable(SphericalTriangle({0.2f, 0.2f, 0}, v0, v1, v2), "in the triangle");
    // On a vertex; a triangle with collinear vertices.
    expect_not_samplable(SphericalTriangle(v1, v0, v1, v2), "on a vertex");
    EXPECT_EQ(TriangleSolidAngle({0, 0, 1}, v0, v1, {2, 0, 0}), 0);
    expect_not_samplable(SphericalTriangle({0, 0, 1}, v0, v1, {2, 0, 0}), "collinear");
    // Too small (1e-6 sr) and too close to a hemisphere.
    const SphericalTriangle tiny({0, 0, 100}, v0, v1, v2);
    EXPECT_NEAR(tiny.solid_angle(), 0.5e-4f, 1e-7f);
    expect_not_samplable(tiny, "tiny");
    const SphericalTriangle huge({0.1f, 0.1f, 1e-3f}, {-10, -10, 0}, {20, -10, 0}, {0, 20, 0});
    EXPECT_GT(huge.solid_angle(), kMaxSphericalTriangleSolidAngle);
    expect_not_samplable(huge, "nearly a hemisphere");
}

// The cheap bound that lets far triangles skip the exact solid angle never changes the decision:
// for random triangles seen from distances where their solid angles straddle the threshold,
// samplable() is exactly "the solid angle is within [min, max]".
TEST(SphericalTriangleTest, FarTriangleShortcutKeepsTheThreshold) {
    int samplable = 0, small = 0;
    for (int i = 0; i < 20000; ++i) {
        Sampler sampler(7, i, 0, 0);
        const auto point = [&sampler] {
            return Vec3(sampler.Get1D(), sampler.Get1D(), sampler.Get1D()) * 2.0f - Vec3(1, 1, 1);
        };
        const Vec3 v0 = point(), v1 = point(), v2 = point();
        // Distances from 1 to 1000 (log-uniform) in a random direction.
        const float distance = std::pow(1000.0f, sampler.Get1D());
        const Vec3 p = Normalize(point()) * distance;
        const float omega = TriangleSolidAngle(p, v0, v1, v2);
        // Leave out solid angles within rounding of the threshold, where float and double differ.
        if (std::abs(omega / kMinSphericalTriangleSolidAngle - 1) < 1e-4f) continue;
        const bool in_range =
            omega >= kMinSphericalTriangleSolidAngle && omega <= kMaxSphericalTriangleSolidAngle;
        const SphericalTriangle st(p, v0, v1, v2);
        EXPECT_EQ(st.samplable(), in_range) << "case " << i << " solid angle " << omega;
        (in_range ? samplable : small) += 1;
    }
    EXPECT_GT(samplable, 1000);
    EXPECT_GT(small, 1000);
}

// The barycentrics (of v1, v2) where the ray p + t w meets the triangle's plane (Moller-Trumbore
// in double), if it meets it in front of p.
std::optional<std::array<double, 2>> HitBarycentrics(const TriangleCase& c, const Vec3& wi) {
    const Vec3d w(wi), v0(c.v0), e1 = Vec3d(c.v1) - v0, e2 = Vec3d(c.v2) - v0;
    const Vec3d s1 = Cross(w, e2);
    const double divisor = Dot(s1, e1);
    if (divisor == 0) return std::nullopt;
    const Vec3d d = Vec3d(c.p) - v0;
    const Vec3d s2 = Cross(d, e1);
    if (Dot(e2, s2) / divisor <= 0) return std::nullopt;  // t <= 0
    return std::array<double, 2>{Dot(d, s1) / divisor, Dot(w, s2) / divisor};
}

class SphericalTriangleSamplingTest : public ::testing::TestWithParam<TriangleCase> {};

// Every sample's ray hits the triangle at the returned point, and the directions are uniform in
// solid angle: the triangle is cut into 8 x 8 sub-triangles, each of which must receive samples
// in proportion to its own solid angle (an independent formula, checked against quadrature
// above), whatever its share of the triangle's area.
TEST_P(SphericalTriangleSamplingTest, UniformInSolidAngleAndOnTheTriangle) {
    const TriangleCase& c = GetParam();
    const SphericalTriangle st(c.p, c.v0, c.v1, c.v2);
    ASSERT_TRUE(st.samplable()) << "solid angle " << st.solid_angle();
    EXPECT_FLOAT_EQ(st.Pdf(), 1 / TriangleSolidAngle(c.p, c.v0, c.v1, c.v2));

    constexpr int k = 8;
    std::vector<std::array<Vec3, 3>> cells;
    std::vector<std::array<std::array<int, 2>, k>> cell_of(k);  // [i][j][upper]
    const auto vertex = [&](int i, int j) {
        const Vec3d v0(c.v0);
        return Vec3(v0 + (Vec3d(c.v1) - v0) * (double(i) / k) +
                    (Vec3d(c.v2) - v0) * (double(j) / k));
    };
    for (int i = 0; i < k; ++i) {
        for (int j = 0; i + j < k; ++j) {
            cell_of[size_t(i)][size_t(j)][0] = int(cells.size());
            cells.push_back({vertex(i, j), vertex(i + 1, j), vertex(i, j + 1)});
            if (i + j < k - 1) {
                cell_of[size_t(i)][size_t(j)][1] = int(cells.size());
                cells.push_back({vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1)});
            }
        }
    }

    constexpr int kSamples = 400'000;
    std::vector<double> observed(cells.size(), 0.0);
    int misses = 0;
    double max_point_error = 0, max_invert_error = 0;
    for (int n = 0; n < kSamples; ++n) {
        Sampler sampler(std::hash<std::string>{}(c.name), 0, 0, uint64_t(n));
        const Vec2 u = sampler.Get2D();
        const SphericalTriangleSample s = st.Sample(u);
        ASSERT_NEAR(Length(s.wi), 1, 1e-6);
        ASSERT_EQ(s.pdf, st.Pdf());
        const auto b = HitBarycentrics(c, s.wi);
        // Float directions: allow a 1e-4 fraction of the triangle's edges.
        constexpr double kSlack = 1e-4;
        if (!b || (*b)[0] < -kSlack || (*b)[1] < -kSlack || (*b)[0] + (*b)[1] > 1 + kSlack) {
            ++misses;
            continue;
        }
        const double b1 = std::clamp((*b)[0], 0.0, 1.0), b2 = std::clamp((*b)[1], 0.0, 1.0);
        const Vec3d hit =
            Vec3d(c.v0) + (Vec3d(c.v1) - Vec3d(c.v0)) * b1 + (Vec3d(c.v2) - Vec3d(c.v0)) * b2;
        max_point_error =
            std::max(max_point_error, Length(hit - Vec3d(s.point)) / Length(hit - Vec3d(c.p)));
        const int i = std::min(int(b1 * k), k - 1), j = std::min(int(b2 * k), k - 1 - i);
        const bool upper = b1 * k - i + b2 * k - j > 1 && i + j < k - 1;
        ++observed[size_t(cell_of[size_t(i)][size_t(j)][upper ? 1 : 0])];

        if (u.x > 0.01f && u.x < 0.99f && u.y > 0.01f && u.y < 0.99f) {
            const Vec2 inverted = st.Invert(s.wi);
            max_invert_error = std::max({max_invert_error, double(std::abs(inverted.x - u.x)),
                                         double(std::abs(inverted.y - u.y))});
        }
    }
    EXPECT_EQ(misses, 0);
    // The returned point is where the direction meets the triangle, to float precision.
    EXPECT_LT(max_point_error, 1e-5);
    // Invert undoes Sample up to the float rounding of the direction: 1e-7 rad over an angular
    // size down to 1e-2 rad.
    EXPECT_LT(max_invert_error, 1e-4);
    std::printf("%-16s point error %.2g invert error %.2g\n", c.name.c_str(), max_point_error,
                max_invert_error);

    std::vector<double> expected(cells.size());
    double total = 0;
    for (size_t i = 0; i < cells.size(); ++i) {
        total += expected[i] = TriangleSolidAngle(c.p, cells[i][0], cells[i][1], cells[i][2]);
    }
    EXPECT_NEAR(total, st.solid_angle(), 1e-5 * st.solid_angle());
    for (double& e : expected) e *= kSamples / total;
    testing::ExpectCountsMatch(observed, expected, c.name, int(Cases().size()));
}

INSTANTIATE_TEST_SUITE_P(Triangles, SphericalTriangleSamplingTest, ::testing::ValuesIn(Cases()),
                         [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace lf
