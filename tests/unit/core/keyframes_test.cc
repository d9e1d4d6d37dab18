#include "lf/core/keyframes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace lf {
namespace {

Keyframes Make(Interpolation interpolation, KeyframeKind kind, int width, std::vector<double> times,
               std::vector<double> values) {
    absl::StatusOr<Keyframes> k =
        Keyframes::Create(interpolation, kind, width, std::move(times), std::move(values), "test");
    EXPECT_TRUE(k.ok()) << k.status();
    return *std::move(k);
}

TEST(Keyframes, LinearTranslationAndScaleLerpBetweenKeys) {
    const Keyframes k = Make(Interpolation::kLinear, KeyframeKind::kVector, 3, {1, 3, 4},
                             {0, 0, 0, 2, -4, 6, 2, 0, 1});
    // Between t = 1 and t = 3 at 2.5: a quarter of the way from the end, (1 - s) a + s b.
    const double s = (2.5 - 1) / 2;
    const std::vector<double> v = k.At(2.5);
    EXPECT_NEAR(v[0], s * 2, 1e-15);
    EXPECT_NEAR(v[1], s * -4, 1e-15);
    EXPECT_NEAR(v[2], s * 6, 1e-15);
    const std::vector<double> w = k.At(3.5);
    EXPECT_NEAR(w[1], -2, 1e-15);
    EXPECT_NEAR(w[2], 3.5, 1e-15);
    // Outside the keys the channel holds its first and last values.
    EXPECT_EQ(k.At(-10), (std::vector<double>{0, 0, 0}));
    EXPECT_EQ(k.At(1), (std::vector<double>{0, 0, 0}));
    EXPECT_EQ(k.At(99), (std::vector<double>{2, 0, 1}));
}

TEST(Keyframes, StepHoldsEachKeyUntilTheNext) {
    const Keyframes k = Make(Interpolation::kStep, KeyframeKind::kVector, 3, {0, 1, 2},
                             {1, 1, 1, 2, 2, 2, 5, 5, 5});
    EXPECT_EQ(k.At(0.999)[0], 1);
    EXPECT_EQ(k.At(1)[0], 2);
    EXPECT_EQ(k.At(1.5)[0], 2);
    EXPECT_EQ(k.At(2)[0], 5);
}

TEST(Keyframes, CubicSplineIsTheSpecificationsHermite) {
    // f(t) = t^3 - t at keys 0, 2 and 3 with its derivatives 3t^2 - 1 as tangents: a cubic
    // Hermite through exact values and slopes reproduces the cubic itself between keys.
    const auto f = [](double t) { return t * t * t - t; };
    const auto df = [](double t) { return 3 * t * t - 1; };
    std::vector<double> values;
    for (double t : {0.0, 2.0, 3.0}) {
        // in-tangent, value, out-tangent, each a vec3 (f, 2f, -f).
        for (double x : {df(t), f(t), df(t)}) {
            values.insert(values.end(), {x, 2 * x, -x});
        }
    }
    const Keyframes k =
        Make(Interpolation::kCubicSpline, KeyframeKind::kVector, 3, {0, 2, 3}, values);
    for (double t : {0.3, 1.0, 1.7, 2.25, 2.9}) {
        const std::vector<double> v = k.At(t);
        EXPECT_NEAR(v[0], f(t), 1e-12) << t;
        EXPECT_NEAR(v[1], 2 * f(t), 1e-12) << t;
        EXPECT_NEAR(v[2], -f(t), 1e-12) << t;
    }
    // The specification's formula with unequal in and out tangents, written out here: between
    // key 0 (value 1, out-tangent 4) and key 1 (value 3, in-tangent -2), interval 2.
    const Keyframes g =
        Make(Interpolation::kCubicSpline, KeyframeKind::kVector, 1, {1, 3}, {9, 1, 4, -2, 3, 7});
    const double s = 0.3, td = 2;
    const double expected = (2 * s * s * s - 3 * s * s + 1) * 1 +
                            td * (s * s * s - 2 * s * s + s) * 4 +
                            (-2 * s * s * s + 3 * s * s) * 3 + td * (s * s * s - s * s) * -2;
    EXPECT_NEAR(g.At(1 + s * td)[0], expected, 1e-14);
    // Outside: the values, never the tangents.
    EXPECT_EQ(g.At(0)[0], 1);
    EXPECT_EQ(g.At(5)[0], 3);
}

// Unit quaternion of `angle` radians about +z.
std::vector<double> AboutZ(double angle) {
    return {0, 0, std::sin(angle / 2), std::cos(angle / 2)};
}

void ExpectSameRotation(const std::vector<double>& q, const std::vector<double>& expected) {
    // q and -q are the same rotation.
    const double dot =
        q[0] * expected[0] + q[1] * expected[1] + q[2] * expected[2] + q[3] * expected[3];
    EXPECT_NEAR(std::abs(dot), 1, 1e-12) << q[0] << " " << q[1] << " " << q[2] << " " << q[3];
    EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1, 1e-12);
}

TEST(Keyframes, LinearRotationSlerpsAlongTheShortestArc) {
    const double pi = std::numbers::pi;
    // 0 to 120 degrees about z: a third of the way is 40 degrees, at constant angular speed.
    std::vector<double> values = AboutZ(0);
    const std::vector<double> end = AboutZ(2 * pi / 3);
    values.insert(values.end(), end.begin(), end.end());
    const Keyframes k = Make(Interpolation::kLinear, KeyframeKind::kRotation, 4, {0, 3}, values);
    ExpectSameRotation(k.At(1), AboutZ(2 * pi / 9));
    // The same end rotation written as -q (the long way round as a 4-vector): still 40 degrees,
    // not the 140 of the other arc.
    std::vector<double> flipped = AboutZ(0);
    for (double c : end) flipped.push_back(-c);
    const Keyframes f = Make(Interpolation::kLinear, KeyframeKind::kRotation, 4, {0, 3}, flipped);
    ExpectSameRotation(f.At(1), AboutZ(2 * pi / 9));
    // 300 degrees about z is the same rotation as -60: the shortest arc turns backwards.
    std::vector<double> wrap = AboutZ(0);
    for (double c : AboutZ(5 * pi / 3)) wrap.push_back(c);
    const Keyframes w = Make(Interpolation::kLinear, KeyframeKind::kRotation, 4, {0, 1}, wrap);
    ExpectSameRotation(w.At(0.5), AboutZ(-pi / 6));
}

TEST(Keyframes, InterpolatedRotationsAreNormalised) {
    // Unnormalised keys (glTF asks for unit ones; quantised files come close) and a cubic
    // spline between them: the result is a unit quaternion.
    const Keyframes step =
        Make(Interpolation::kStep, KeyframeKind::kRotation, 4, {0, 1}, {0, 0, 2, 0, 0, 0, 0, 3});
    ExpectSameRotation(step.At(0.5), {0, 0, 1, 0});
    const std::vector<double> a = AboutZ(0), b = AboutZ(1);
    std::vector<double> values;
    for (const auto* q : {&a, &b}) {
        for (int i = 0; i < 3; ++i) {
            for (double c : *q) values.push_back(i == 1 ? c : 0.5);
        }
    }
    const Keyframes cubic =
        Make(Interpolation::kCubicSpline, KeyframeKind::kRotation, 4, {0, 1}, values);
    const std::vector<double> q = cubic.At(0.4);
    EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1, 1e-12);
}

TEST(Keyframes, BadSamplersAreRefusedNamingWhere) {
    const auto error = [](Interpolation i, std::vector<double> times, std::vector<double> values,
                          KeyframeKind kind = KeyframeKind::kVector) {
        const int width = kind == KeyframeKind::kRotation ? 4 : 1;
        absl::StatusOr<Keyframes> k = Keyframes::Create(
            i, kind, width, std::move(times), std::move(values), "animations[2].samplers[1]");
        EXPECT_FALSE(k.ok());
        EXPECT_EQ(k.status().code(), absl::StatusCode::kInvalidArgument);
        return std::string(k.status().message());
    };
    EXPECT_EQ(error(Interpolation::kLinear, {0, 1, 1}, {0, 1, 2}),
              "animations[2].samplers[1]: input times are not strictly increasing: time 2 is 1 "
              "after 1");
    EXPECT_EQ(error(Interpolation::kLinear, {0, 2, 1}, {0, 1, 2}),
              "animations[2].samplers[1]: input times are not strictly increasing: time 2 is 1 "
              "after 2");
    EXPECT_EQ(error(Interpolation::kLinear, {0, NAN}, {0, 1}),
              "animations[2].samplers[1]: input time 1 is nan");
    EXPECT_EQ(error(Interpolation::kLinear, {0, 1}, {0, NAN}),
              "animations[2].samplers[1]: output keyframe 1 (at 1 s) number 0 is nan");
    EXPECT_EQ(error(Interpolation::kLinear, {0, 1}, {0, INFINITY}),
              "animations[2].samplers[1]: output keyframe 1 (at 1 s) number 0 is inf");
    EXPECT_EQ(error(Interpolation::kCubicSpline, {0, 1}, {0, 1}),
              "animations[2].samplers[1]: output has 2 numbers for 2 keyframes; expected 6 "
              "(CUBICSPLINE: in-tangent, value, out-tangent)");
    EXPECT_EQ(error(Interpolation::kCubicSpline, {0}, {0, 1, 2}),
              "animations[2].samplers[1]: CUBICSPLINE needs at least 2 keyframes");
    EXPECT_EQ(error(Interpolation::kLinear, {}, {}),
              "animations[2].samplers[1]: input has no keyframes");
    EXPECT_EQ(error(Interpolation::kLinear, {0}, {0, 0, 0, 0}, KeyframeKind::kRotation),
              "animations[2].samplers[1]: output keyframe 0 (at 0 s) is the zero quaternion");
    EXPECT_EQ(
        std::string(ParseInterpolation("SMOOTH", "animations[0].samplers[3]").status().message()),
        "animations[0].samplers[3]: interpolation \"SMOOTH\" is unknown; expected LINEAR, "
        "STEP or CUBICSPLINE");
}

}  // namespace
}  // namespace lf
