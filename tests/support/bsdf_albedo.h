// The directional albedo of a BSDF estimated through its own sampling, the mean of
// f |cos| / pdf: the white furnace of a single scattering event.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "lf/core/sampler.h"
#include "lf/kernels/bsdf.h"
#include "sphere_quadrature.h"

namespace lf::testing {

inline Vec3 UniformSphere(const Vec2& u) {
    const float z = 1 - 2 * u.x;
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    const float phi = 2 * std::numbers::pi_v<float> * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

struct Albedo {
    Rgb mean;
    Rgb stderr_;        // standard error of the mean per channel
    double max_weight;  // largest single-sample weight over channels
};

// Energy, not radiance: the 1/eta^2 compression of radiance refracted into another medium
// (BsdfSample::eta) is undone, so a lossless interface has albedo one from either side.
inline Albedo EstimateAlbedo(const Bsdf& bsdf, const Vec3& wo, uint64_t seed, int n) {
    std::array<double, 3> sum{}, sum2{};
    double max_weight = 0;
    for (int i = 0; i < n; ++i) {
        Sampler sampler(seed, 0, 0, uint64_t(i));
        const float uc = sampler.Get1D();
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, sampler.Get2D());
        if (!bs) continue;  // a failed sample carries no energy
        const Rgb w = bs->f * (std::abs(bs->wi.z) * bs->eta * bs->eta / bs->pdf);
        EXPECT_TRUE(w.IsFinite());
        for (int c = 0; c < 3; ++c) {
            sum[size_t(c)] += w[c];
            sum2[size_t(c)] += double(w[c]) * w[c];
            max_weight = std::max(max_weight, double(w[c]));
        }
    }
    Albedo a{};
    a.max_weight = max_weight;
    for (int c = 0; c < 3; ++c) {
        const double mean = sum[size_t(c)] / n;
        const double var = std::max(0.0, sum2[size_t(c)] / n - mean * mean);
        a.mean[c] = float(mean);
        a.stderr_[c] = float(std::sqrt(var / (n - 1)));
    }
    return a;
}

// Incident directions at cos theta 1 .. 0.01, front and back.
inline std::vector<Vec3> FurnaceDirections() {
    std::vector<Vec3> wos;
    for (float cos : {1.0f, 0.9f, 0.7f, 0.5f, 0.3f, 0.15f, 0.05f, 0.01f}) {
        const Vec3 w = Spherical(std::acos(cos), 0.7);
        wos.push_back(w);
        wos.push_back(Vec3(w.x, w.y, -w.z));
    }
    return wos;
}

inline constexpr int kFurnaceSamples = 20000;

}  // namespace lf::testing
