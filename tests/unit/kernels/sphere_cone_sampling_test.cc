#include "lf/kernels/sphere_cone_sampling.h"

#include <gtest/gtest.h>

#include <algorithm>
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

struct SphereCase {
    std::string name;
    Vec3 p, center;
    float radius;
};

constexpr int kSamples = 300'000;

// Distance along the unit ray p + t w to its first hit on the sphere in front of p, in double.
std::optional<double> FirstHit(const Vec3& p, const Vec3& w, const Vec3& center, float radius) {
    const Vec3d o = Vec3d(p) - Vec3d(center), d = Normalize(Vec3d(w));
    const double b = Dot(o, d), c = LengthSquared(o) - double(radius) * radius;
    const double disc = b * b - c;
    if (disc < 0) return std::nullopt;
    const double root = std::sqrt(disc);
    const double t0 = -b - root, t1 = -b + root;
    if (t0 > 0) return t0;
    if (t1 > 0) return t1;
    return std::nullopt;
}

// Every sample is a point on the sphere, visible from p, on the ray p + t wi, with the density
// SphereConePdf gives it; returns the sampled directions.
std::vector<Vec3> SampleAndCheck(const SphereCase& c) {
    std::vector<Vec3> directions;
    double max_off_ray = 0, max_off_sphere = 0, max_pdf_error = 0;
    int failed = 0, hidden = 0;
    for (int n = 0; n < kSamples; ++n) {
        Sampler sampler(std::hash<std::string>{}(c.name), 0, 0, uint64_t(n));
        const std::optional<SphereConeSample> s =
            SampleSphereCone(c.p, c.center, c.radius, sampler.Get2D());
        if (!s) {
            ++failed;
            continue;
        }
        EXPECT_NEAR(Length(s->wi), 1, 1e-6);
        EXPECT_LT(Length(Vec3d(s->normal) - Normalize(Vec3d(s->point) - Vec3d(c.center))), 1e-5);
        const double pdf = SphereConePdf(c.p, c.center, c.radius, s->point);
        max_pdf_error = std::max(max_pdf_error, std::abs(pdf / s->pdf - 1));
        // Distances relative to the scene's scale (the point is a float).
        const Vec3d to_point = Vec3d(s->point) - Vec3d(c.p);
        const double length = Length(to_point);
        const double scale = std::max(length, double(c.radius));
        max_off_ray = std::max(max_off_ray, Length(Cross(to_point, Vec3d(s->wi))) / scale);
        max_off_sphere = std::max(
            max_off_sphere, std::abs(Length(Vec3d(s->point) - Vec3d(c.center)) - c.radius) / scale);
        // Visible: no part of the sphere in front of it along the ray (the outward normal does
        // not face away from p), to float precision; from inside, every point is seen.
        if (Dot(Vec3d(s->normal), to_point) > 1e-5 * length &&
            LengthSquared(Vec3d(c.p) - Vec3d(c.center)) > double(c.radius) * c.radius) {
            ++hidden;
        }
        directions.push_back(s->wi);
    }
    EXPECT_EQ(failed, 0) << c.name;
    EXPECT_EQ(hidden, 0) << c.name;
    EXPECT_LT(max_off_ray, 1e-6) << c.name;
    EXPECT_LT(max_off_sphere, 1e-6) << c.name;
    // SphereConePdf recomputes the normal from the float point: float agreement.
    EXPECT_LT(max_pdf_error, 1e-5) << c.name;
    return directions;
}

std::vector<SphereCase> OutsideCases() {
    return {
        {"Near", {0.3f, 1.2f, -0.4f}, {0, 0, 0}, 1},
        {"JustOutside", {0, 0, 1.001f}, {0, 0, 0}, 1},
        {"Far", {10, -3, 4}, {1, 1, 1}, 0.8f},
        {"Tiny", {6, 8, 0}, {0, 0, 0}, 1e-3f},
    };
}

// Directions from outside are uniform over the cone: binned by their angle to the axis (ten
// equal steps of angle up to the tangent) and azimuth (eight), each cell holds its share of the
// cone's solid angle.
class SphereConeOutsideTest : public ::testing::TestWithParam<SphereCase> {};

TEST_P(SphereConeOutsideTest, UniformOverTheVisibleCone) {
    const SphereCase& c = GetParam();
    const std::vector<Vec3> directions = SampleAndCheck(c);
    const Vec3d axis = Normalize(Vec3d(c.center) - Vec3d(c.p));
    const double sin_max = c.radius / Length(Vec3d(c.center) - Vec3d(c.p));
    const double theta_max = std::asin(sin_max);
    // An azimuth reference independent of the sampler's frame.
    const Vec3d x =
        Normalize(Cross(axis, std::abs(axis.x) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0)));
    const Vec3d y = Cross(axis, x);
    constexpr int kTheta = 10, kPhi = 8;
    // One more row for directions outside the cone, which must stay empty.
    std::vector<double> observed((kTheta + 1) * kPhi, 0.0), expected(observed.size(), 0.0);
    for (const Vec3& wf : directions) {
        const Vec3d w(wf);
        const double theta = std::atan2(Length(Cross(w, axis)), Dot(w, axis));
        double phi = std::atan2(Dot(w, y), Dot(w, x));
        if (phi < 0) phi += 2 * kPi;
        // Float directions: a 1e-3 fraction of the cone's angle counts as inside it.
        const int ti = theta > theta_max * (1 + 1e-3)
                           ? kTheta
                           : std::min(int(theta / theta_max * kTheta), kTheta - 1);
        const int pi = std::min(int(phi / (2 * kPi) * kPhi), kPhi - 1);
        ++observed[size_t(ti * kPhi + pi)];
    }
    // 1 - cos in the stable form sin^2 / (1 + cos).
    const auto one_minus_cos = [](double theta) {
        const double s = std::sin(theta);
        return s * s / (1 + std::cos(theta));
    };
    for (int ti = 0; ti < kTheta; ++ti) {
        const double band =
            one_minus_cos(theta_max * (ti + 1) / kTheta) - one_minus_cos(theta_max * ti / kTheta);
        for (int pi = 0; pi < kPhi; ++pi) {
            expected[size_t(ti * kPhi + pi)] =
                band / one_minus_cos(theta_max) / kPhi * double(directions.size());
        }
    }
    testing::ExpectCountsMatch(observed, expected, c.name, int(OutsideCases().size()) + 2);
}

INSTANTIATE_TEST_SUITE_P(Spheres, SphereConeOutsideTest, ::testing::ValuesIn(OutsideCases()),
                         [](const auto& info) { return info.param.name; });

// From inside, the density per solid angle follows the area density: binned on a (theta, phi)
// grid, each cell holds the integral of SphereConePdf over it.
class SphereConeInsideTest : public ::testing::TestWithParam<SphereCase> {};

TEST_P(SphereConeInsideTest, AreaDensityPerSolidAngle) {
    const SphereCase& c = GetParam();
    const std::vector<Vec3> directions = SampleAndCheck(c);
    constexpr int kTheta = 10, kPhi = 20;
    std::vector<double> observed(kTheta * kPhi, 0.0), expected(observed.size(), 0.0);
    for (const Vec3& w : directions) {
        const double theta = std::acos(std::clamp(double(w.z), -1.0, 1.0));
        double phi = std::atan2(double(w.y), double(w.x));
        if (phi < 0) phi += 2 * kPi;
        const int ti = std::min(int(theta / kPi * kTheta), kTheta - 1);
        const int pi = std::min(int(phi / (2 * kPi) * kPhi), kPhi - 1);
        ++observed[size_t(ti * kPhi + pi)];
    }
    const auto pdf = [&](const Vec3& w) {
        const double t = *FirstHit(c.p, w, c.center, c.radius);
        return double(SphereConePdf(c.p, c.center, c.radius, c.p + w * float(t)));
    };
    double total = 0;
    for (int ti = 0; ti < kTheta; ++ti) {
        for (int pi = 0; pi < kPhi; ++pi) {
            const double mass = testing::IntegrateSolidAngle(
                pdf, ti * kPi / kTheta, (ti + 1) * kPi / kTheta, pi * 2 * kPi / kPhi,
                (pi + 1) * 2 * kPi / kPhi, 2, 1e-7);
            total += mass;
            expected[size_t(ti * kPhi + pi)] = mass * double(directions.size());
        }
    }
    EXPECT_NEAR(total, 1, 1e-4) << c.name;
    testing::ExpectCountsMatch(observed, expected, c.name, int(OutsideCases().size()) + 2);
}

INSTANTIATE_TEST_SUITE_P(Spheres, SphereConeInsideTest,
                         ::testing::Values(SphereCase{"Centre", {1, 2, 3}, {1, 2, 3}, 2},
                                           SphereCase{
                                               "OffCentre", {0.5f, -0.3f, 0.4f}, {0, 0, 0}, 1}),
                         [](const auto& info) { return info.param.name; });

TEST(SphereConeSamplingTest, ConeDensityFromOutside) {
    // 1 / (2 pi (1 - cos theta_max)), also where cos(theta_max) rounds to 1 in float.
    const double sin_max = 1e-4 / 5;
    const double expected =
        1 / (2 * kPi * (sin_max * sin_max / (1 + std::sqrt(1 - sin_max * sin_max))));
    EXPECT_NEAR(SphereConePdf({0, 0, 5}, {0, 0, 0}, 1e-4f, {0, 0, 1e-4f}), expected,
                1e-6 * expected);
    // Half the sphere of directions seen from the centre's distance sqrt(2) r: theta_max 45 deg.
    EXPECT_NEAR(SphereConePdf({0, 0, std::sqrt(2.0f)}, {0, 0, 0}, 1, {0, 0, 1}),
                1 / (2 * kPi * (1 - std::sqrt(0.5))), 1e-5);
}

TEST(SphereConeSamplingTest, NoSizeNoSample) {
    EXPECT_FALSE(SampleSphereCone({0, 0, 2}, {0, 0, 0}, 0, {0.5f, 0.5f}));
    EXPECT_FALSE(SampleSphereCone({0, 0, 2}, {0, 0, 0}, -1, {0.5f, 0.5f}));
    EXPECT_EQ(SphereConePdf({0, 0, 2}, {0, 0, 0}, 0, {0, 0, 0}), 0);
}

}  // namespace
}  // namespace lf
