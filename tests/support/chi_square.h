// Chi-square goodness of fit of a BSDF's sampling against its density (after pbrt-v4's
// bsdfs_test and Mitsuba's chi2.py), shared by the BSDF tests.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lf/core/sampler.h"
#include "lf/kernels/bsdf.h"
#include "sphere_quadrature.h"

namespace lf::testing {

// Regularised upper incomplete gamma function Q(a, x) (Numerical Recipes' gammq).
inline double GammaQ(double a, double x) {
    if (x <= 0) return 1;
    const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
    if (x < a + 1) {
        double term = 1 / a, sum = term;
        for (int n = 1; n < 1000 && std::abs(term) > std::abs(sum) * 1e-15; ++n) {
            term *= x / (a + n);
            sum += term;
        }
        return 1 - sum * std::exp(log_prefactor);
    }
    constexpr double kTiny = 1e-300;
    double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
    for (int i = 1; i < 1000; ++i) {
        const double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1 / d;
        const double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1) < 1e-15) break;
    }
    return std::exp(log_prefactor) * h;
}

inline double ChiSquarePValue(double chi2, int dof) { return GammaQ(0.5 * dof, 0.5 * chi2); }

// Normal, oblique, grazing and back-side incidence, azimuth off the bin edges, named for test
// case names.
inline std::vector<std::pair<std::string, Vec3>> Chi2IncidentDirections() {
    return {
        {"Normal", Spherical(0, 0)},
        {"Oblique45", Spherical(Radians(45), 0.5)},
        {"Grazing80", Spherical(Radians(80), 2.0)},
        {"Back130", Spherical(Radians(130), 4.0)},
    };
}

inline constexpr int kThetaRes = 10;  // pi / 10 per row: the horizon is a row boundary
inline constexpr int kPhiRes = 2 * kThetaRes;
inline constexpr int kChi2Samples = 1'000'000;
inline constexpr double kMinExpected = 5;
inline constexpr double kSignificance = 0.01;

// The p-value of observed counts against expected ones (summing to the same total) by Pearson's
// chi-square, cells with expected counts below kMinExpected pooled, smallest first. A cell of
// zero expectation must stay (almost) empty: more than 1e-5 of the total there fails the test
// and returns 0.
inline double ChiSquareFit(const std::vector<double>& observed,
                           const std::vector<double>& expected) {
    const size_t cells = observed.size();
    double total = 0;
    for (double o : observed) total += o;
    std::vector<size_t> order(cells);
    for (size_t i = 0; i < cells; ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    double chi2 = 0, pooled_observed = 0, pooled_expected = 0;
    int dof = 0;
    for (size_t i : order) {
        const double e = expected[i], o = observed[i];
        if (e == 0) {
            EXPECT_LE(o, total * 1e-5) << "samples in cell " << i << " of zero density";
            if (o > total * 1e-5) return 0;
        } else if (e < kMinExpected || (pooled_expected > 0 && pooled_expected < kMinExpected)) {
            pooled_observed += o;
            pooled_expected += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            ++dof;
        }
    }
    if (pooled_expected > 0) {
        chi2 += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) /
                pooled_expected;
        ++dof;
    }
    // The counts sum to the sample count: one constraint.
    dof -= 1;
    EXPECT_GT(dof, 0);
    const double p_value = ChiSquarePValue(chi2, dof);
    std::printf("[chi2] chi2 %9.2f dof %3d p %.4f\n", chi2, dof, p_value);
    return p_value;
}

// Expects `observed` counts to be drawn from `expected` (ChiSquareFit) for any histogram: the
// (theta, phi) cells of ExpectSamplingMatchesPdf, the sub-triangles of an emitter, the lights of
// a light BVH. Sidak: a family of `num_tests` such tests keeps the family-wise rate at
// kSignificance.
inline void ExpectCountsMatch(const std::vector<double>& observed,
                              const std::vector<double>& expected, const std::string& name,
                              int num_tests) {
    ASSERT_EQ(observed.size(), expected.size()) << name;
    const double p_value = ChiSquareFit(observed, expected);
    const double level = 1 - std::pow(1 - kSignificance, 1.0 / num_tests);
    std::printf("[chi2] %-28s p %.4f\n", name.c_str(), p_value);
    EXPECT_GT(p_value, level) << name;
}

// Chi-square goodness of fit of bsdf.Sample(wo, ...) against bsdf.Pdf(wo, .) over the sphere;
// `name` seeds the sampler and labels the printed line, and `num_tests` (the size of the family
// of such tests) sets the Sidak-corrected level. A BSDF with delta lobes beside rough ones
// (`with_delta`): Pdf leaves out the delta lobes' pick probabilities, so their samples count as
// mass Pdf does not cover, as failed samples do; without it a delta sample fails the test.
inline void ExpectSamplingMatchesPdf(const Bsdf& bsdf, const Vec3& wo, const std::string& name,
                                     int num_tests, bool with_delta = false) {
    // Observed: histogram of sampled directions; the extra last cell counts failed samples (and
    // delta ones, with_delta).
    constexpr int kCells = kThetaRes * kPhiRes;
    std::vector<double> observed(kCells + 1, 0.0);
    const uint64_t seed = std::hash<std::string>{}(name);
    for (int i = 0; i < kChi2Samples; ++i) {
        Sampler sampler(seed, 0, 0, uint64_t(i));
        const float uc = sampler.Get1D();
        const Vec2 u = sampler.Get2D();
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, u);
        if (!bs) {
            ++observed[kCells];
            continue;
        }
        if (with_delta && bs->delta) {
            ++observed[kCells];
            continue;
        }
        ASSERT_FALSE(bs->delta);
        const double theta = std::acos(std::clamp(double(bs->wi.z), -1.0, 1.0));
        double phi = std::atan2(double(bs->wi.y), double(bs->wi.x));
        if (phi < 0) phi += 2 * kPi;
        const int ti = std::min(int(theta / kPi * kThetaRes), kThetaRes - 1);
        const int pi = std::min(int(phi / (2 * kPi) * kPhiRes), kPhiRes - 1);
        ++observed[size_t(ti * kPhiRes + pi)];
    }

    // Expected: Pdf integrated over each cell, to a small fraction of a count.
    std::vector<double> expected(kCells + 1, 0.0);
    double integral = 0;
    for (int ti = 0; ti < kThetaRes; ++ti) {
        for (int pi = 0; pi < kPhiRes; ++pi) {
            const double p =
                IntegrateSolidAngle([&](const Vec3& wi) { return double(bsdf.Pdf(wo, wi)); },
                                    ti * kPi / kThetaRes, (ti + 1) * kPi / kThetaRes,
                                    pi * 2 * kPi / kPhiRes, (pi + 1) * 2 * kPi / kPhiRes, 4, 1e-7);
            expected[size_t(ti * kPhiRes + pi)] = p * kChi2Samples;
            integral += p;
        }
    }
    // Samples that Sample rejects (or gives a delta lobe) are exactly the mass Pdf does not cover.
    expected[kCells] = std::max(0.0, 1 - integral) * kChi2Samples;

    const double fail_fraction = observed[kCells] / kChi2Samples;
    EXPECT_LE(integral, 1 + 1e-4) << "Pdf integrates to more than one";
    const double fail_sigma =
        std::sqrt(std::max(fail_fraction * (1 - fail_fraction), 1.0 / kChi2Samples) / kChi2Samples);
    EXPECT_NEAR(1 - integral, fail_fraction, 5 * fail_sigma + 1e-4 /* quadrature */)
        << "missing Pdf mass differs from the fraction of failed samples";

    std::printf("[chi2] %-24s integral %.6f failed %.6f\n", name.c_str(), integral, fail_fraction);
    ExpectCountsMatch(observed, expected, name, num_tests);
}

}  // namespace lf::testing
