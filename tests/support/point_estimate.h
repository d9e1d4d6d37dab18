// The radiance along one ray, estimated by n independent samples of a RadianceEstimator, with
// its standard error from the samples' own variance: a single-point render for tests whose
// closed form is known at a few points.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "lf/core/ray.h"
#include "lf/core/rgb.h"
#include "lf/core/sampler.h"
#include "lf/kernels/radiance.h"

namespace lf::testing {

struct PointEstimate {
    double mean[3] = {};
    double standard_error[3] = {};  // of the mean
    double sample_sd[3] = {};       // of one sample
};

inline PointEstimate EstimateRadiance(const RadianceEstimator& estimator, const Ray& ray, int n,
                                      uint64_t seed = 1) {
    double sum[3] = {}, sum2[3] = {};
    RenderStats stats;
    for (int i = 0; i < n; ++i) {
        Sampler sampler(seed, 0, 0, uint64_t(i));
        const Rgb L = estimator.Li(ray, sampler, stats);
        for (int c = 0; c < 3; ++c) {
            sum[c] += L[c];
            sum2[c] += double(L[c]) * L[c];
        }
    }
    PointEstimate e;
    for (int c = 0; c < 3; ++c) {
        e.mean[c] = sum[c] / n;
        const double variance = std::max(0.0, (sum2[c] - sum[c] * e.mean[c]) / (n - 1));
        e.sample_sd[c] = std::sqrt(variance);
        e.standard_error[c] = e.sample_sd[c] / std::sqrt(double(n));
    }
    return e;
}

// Expects each channel of the estimate within k standard errors (and float rounding) of
// `expected`.
inline void ExpectEstimateNear(const PointEstimate& e, const Rgb& expected, double k = 5) {
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(e.mean[c], expected[c], k * e.standard_error[c] + 1e-5 * expected[c])
            << "channel " << c;
    }
}

// A ray from world point `from` towards world point `to`, in the render space of a scene whose
// geometry was moved by -origin.
inline Ray RayBetween(const Vec3d& from, const Vec3d& to, const Vec3d& origin) {
    return {Vec3(from - origin), Vec3(Normalize(to - from))};
}

}  // namespace lf::testing
