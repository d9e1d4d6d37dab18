#include "lf/kernels/fresnel_mix_albedo.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lf {
namespace {

// Midpoint rule over (cos theta_i, phi in [0, pi], doubled by symmetry): Q is smooth, and 256 x
// 128 points put it within 1e-5 of a 4x finer grid.
constexpr int kCosSteps = 256, kPhiSteps = 128;

}  // namespace

const FresnelMixAlbedo& FresnelMixAlbedo::Get() {
    static const FresnelMixAlbedo table;
    return table;
}

FresnelMixAlbedo::FresnelMixAlbedo() : q_(kMuSize) {
    for (int i = 0; i < kMuSize; ++i) {
        const double mu = double(i) / (kMuSize - 1);
        const double so = std::sqrt(1 - mu * mu);
        double sum = 0;
        for (int a = 0; a < kCosSteps; ++a) {
            const double ci = (a + 0.5) / kCosSteps, si = std::sqrt(1 - ci * ci);
            for (int b = 0; b < kPhiSteps; ++b) {
                const double phi = std::numbers::pi * (b + 0.5) / kPhiSteps;
                // wo.h = sqrt((1 + wo.wi) / 2) for unit wo, wi.
                const double cos_oi = mu * ci + so * si * std::cos(phi);
                const double m = 1 - std::sqrt(std::max(0.0, (1 + cos_oi) / 2));
                sum += (m * m) * (m * m) * m * ci;
            }
        }
        // dwi = dcos dphi over phi in [0, 2 pi]; the 1 / pi of the Lambertian base.
        q_[size_t(i)] = float(sum * 2 / (double(kCosSteps) * kPhiSteps));
    }
}

float FresnelMixAlbedo::Q(float mu) const {
    const float x = (mu > 0 ? std::min(mu, 1.0f) : 0.0f) * (kMuSize - 1);  // NaN -> 0
    const int i = std::min(int(x), kMuSize - 2);
    const float t = x - float(i);
    return q_[size_t(i)] + t * (q_[size_t(i + 1)] - q_[size_t(i)]);
}

}  // namespace lf
