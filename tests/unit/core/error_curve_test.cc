// Equal-time comparison of error curves against power laws with known constants, where the
// log-log interpolation is exact, and against a hand-integrated piecewise case.
#include "lf/core/error_curve.h"

#include <gtest/gtest.h>

#include <cmath>

namespace lf {
namespace {

// c t^k at t0, 2 t0, 4 t0, ... (n points), listed backwards to show that order does not matter.
ErrorCurve PowerLaw(double c, double k, double t0, int n) {
    ErrorCurve curve;
    for (int i = n - 1; i >= 0; --i) {
        const double t = t0 * std::ldexp(1.0, i);
        curve.push_back({t, c * std::pow(t, k)});
    }
    return curve;
}

// a = 2 t^-1/2 on [1, 512]; b = 0.5 t^-3/4 on [1.5, 3072]: b / a = t^-1/4 / 4.
TEST(ErrorCurve, PowerLawsCompareExactlyAtEqualTime) {
    const ErrorCurve a = PowerLaw(2, -0.5, 1, 10), b = PowerLaw(0.5, -0.75, 1.5, 12);
    const TimeRange range = CommonTimeRange({a, b}).value();
    EXPECT_DOUBLE_EQ(range.from, 1.5);
    EXPECT_DOUBLE_EQ(range.to, 512);
    // Between the points of a (t = 3 lies between 2 and 4) and of b (t = 100, between 96 and 192).
    for (double t : {1.5, 3.0, 100.0, 512.0}) {
        EXPECT_NEAR(ErrorAtTime(a, t).value(), 2 * std::pow(t, -0.5), 1e-12 * t) << t;
        EXPECT_NEAR(ErrorAtTime(b, t).value() / ErrorAtTime(a, t).value(),
                    0.25 * std::pow(t, -0.25), 1e-12)
            << t;
    }
    // exp(mean over u = log t in [log 1.5, log 512] of (log 0.25 - u / 4)).
    const double expected = 0.25 * std::exp(-0.25 * 0.5 * (std::log(1.5) + std::log(512.0)));
    EXPECT_NEAR(MeanRatioOverTime(a, b, range).value(), expected, 1e-12);
    EXPECT_NEAR(MeanRatioOverTime(b, a, range).value(), 1 / expected, 1e-12);
    EXPECT_NEAR(MeanRatioOverTime(a, a, range).value(), 1, 1e-12);
    // A range of one time is the ratio there.
    EXPECT_NEAR(MeanRatioOverTime(a, b, {8, 8}).value(), 0.25 * std::pow(8.0, -0.25), 1e-12);
}

// a is flat at 1; b falls from 1 at t = 1 to 1/4 at t = 4 (slope -1 in log-log), then stays at
// 1/4 up to t = 16. Over [1, 16] in log t: half the range with mean log ratio log(1/4) / 2,
// half at log(1/4): mean 3/4 log(1/4), ratio 4^-3/4.
TEST(ErrorCurve, MeanRatioIntegratesAPiecewiseCurveExactly) {
    const ErrorCurve a = {{1, 1}, {16, 1}};
    const ErrorCurve b = {{1, 1}, {4, 0.25}, {16, 0.25}};
    EXPECT_NEAR(MeanRatioOverTime(a, b, {1, 16}).value(), std::pow(4.0, -0.75), 1e-12);
    EXPECT_NEAR(MeanRatioOverTime(a, b, {4, 16}).value(), 0.25, 1e-12);
    EXPECT_NEAR(ErrorAtTime(b, 2).value(), 0.5, 1e-12);
}

TEST(ErrorCurve, RefusesWhatItCannotCompare) {
    const ErrorCurve a = PowerLaw(1, -0.5, 1, 4);  // 1 to 8 s
    const ErrorCurve late = PowerLaw(1, -0.5, 16, 4);
    const absl::StatusOr<TimeRange> none = CommonTimeRange({a, late});
    ASSERT_FALSE(none.ok());
    EXPECT_NE(none.status().message().find("share no time"), std::string::npos) << none.status();
    EXPECT_FALSE(CommonTimeRange({}).ok());
    EXPECT_FALSE(CommonTimeRange({a, {}}).ok());
    EXPECT_FALSE(CommonTimeRange({a, {{1, 0}, {2, 1}}}).ok());
    const absl::StatusOr<double> outside = ErrorAtTime(a, 9);
    ASSERT_FALSE(outside.ok());
    EXPECT_NE(outside.status().message().find("outside the curve's 1 to 8 s"), std::string::npos)
        << outside.status();
    EXPECT_FALSE(MeanRatioOverTime(a, late, {1, 8}).ok());
    EXPECT_FALSE(MeanRatioOverTime(a, a, {4, 2}).ok());
}

}  // namespace
}  // namespace lf
