#include "lf/kernels/ggx_albedo.h"

#include <algorithm>
#include <cmath>

#include "lf/kernels/microfacet.h"
#include "tbb/parallel_for.h"
#include "tbb/task_arena.h"

namespace lf {
namespace {

// Midpoint grid over the visible-normal sampling square per table entry. The integrand G2/G1
// F is smooth there apart from the cut where reflections fall below the horizon. With 40 x 40
// points and the node spacing below, E (interpolated) lies within 2.5e-3 under and 5e-3 over a
// 512 x 512 reference for mu >= 0.01, the worst cases at grazing incidence on nearly smooth
// surfaces (GgxAlbedo test); building it takes about 0.3 s of one core.
constexpr int kQuadrature = 40;

// Nodes crowd towards grazing incidence, where E changes fastest (shadowing of narrow lobes).
float MuAt(int i) {
    const float s = float(i) / (GgxAlbedo::kMuSize - 1);
    return s * s;
}
float RoughnessAt(int j) { return float(j) / (GgxAlbedo::kRoughnessSize - 1); }

}  // namespace

const GgxAlbedo& GgxAlbedo::Get() {
    static const GgxAlbedo table;
    return table;
}

GgxAlbedo::GgxAlbedo()
    : a_(size_t(kMuSize * kRoughnessSize)),
      b_(a_.size()),
      a_average_(size_t(kRoughnessSize)),
      b_average_(size_t(kRoughnessSize)) {
    // Rows are independent: one task per roughness. Isolated, because the first Get() may come
    // from inside a render's parallel loop: a thread waiting here must not pick up one of that
    // loop's tasks, which would re-enter this static initialiser.
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(0, kRoughnessSize, [&](int j) {
            const float r = RoughnessAt(j);
            const MicrofacetDistribution distribution(Material::Distribution::kGgx, r * r);
            for (int i = 0; i < kMuSize; ++i) {
                // At mu = 0 exactly nothing is seen; the limit is taken just above it.
                const float mu = std::max(MuAt(i), 1e-4f);
                const Vec3 wo(std::sqrt(1 - mu * mu), 0, mu);
                double a = 0, b = 0;
                for (int y = 0; y < kQuadrature; ++y) {
                    for (int x = 0; x < kQuadrature; ++x) {
                        const Vec2 u((x + 0.5f) / kQuadrature, (y + 0.5f) / kQuadrature);
                        const Vec3 wm = distribution.SampleWm(wo, u);
                        const float cos_om = Dot(wo, wm);
                        if (cos_om <= 0) continue;
                        const Vec3 wi = wm * (2 * cos_om) - wo;
                        if (wi.z <= 0) continue;
                        // Visible-normal sampling leaves the weight G2 / G1(wo).
                        const double w = distribution.G(wo, wi) / distribution.G1(wo);
                        const double m = 1 - std::min(1.0f, cos_om);
                        const double m5 = (m * m) * (m * m) * m;
                        a += w * (1 - m5);
                        b += w * m5;
                    }
                }
                const double n = double(kQuadrature) * kQuadrature;
                a_[size_t(j * kMuSize + i)] = float(a / n);
                b_[size_t(j * kMuSize + i)] = float(b / n);
            }
            // 2 int E(mu) mu dmu of the piecewise-linear E, exactly, segment by segment.
            double a_avg = 0, b_avg = 0;
            for (int i = 0; i + 1 < kMuSize; ++i) {
                const double m0 = MuAt(i), m1 = MuAt(i + 1), h = m1 - m0;
                const double w0 = h * (2 * m0 + m1) / 6, w1 = h * (m0 + 2 * m1) / 6;
                a_avg +=
                    2 * (w0 * a_[size_t(j * kMuSize + i)] + w1 * a_[size_t(j * kMuSize + i + 1)]);
                b_avg +=
                    2 * (w0 * b_[size_t(j * kMuSize + i)] + w1 * b_[size_t(j * kMuSize + i + 1)]);
            }
            a_average_[size_t(j)] = float(a_avg);
            b_average_[size_t(j)] = float(b_avg);
        });
    });
}

GgxAlbedo::Roughness GgxAlbedo::At(float r) {
    const float x = (r > 0 ? std::min(r, 1.0f) : 0.0f) * (kRoughnessSize - 1);  // NaN -> 0
    const int index = std::min(int(x), kRoughnessSize - 2);
    return {index, x - float(index)};
}

float GgxAlbedo::E(float mu, Roughness r, float f0) const {
    mu = mu > 0 ? std::min(mu, 1.0f) : 0.0f;  // NaN -> 0
    const int i = std::min(int(std::sqrt(mu) * (kMuSize - 1)), kMuSize - 2);
    // Linear in mu itself between nodes, which is what Average integrates.
    const float mu0 = MuAt(i), mu1 = MuAt(i + 1);
    const float t = std::clamp((mu - mu0) / (mu1 - mu0), 0.0f, 1.0f);
    const auto at = [&](const std::vector<float>& table, int j) {
        const float* row = &table[size_t(j * kMuSize)];
        return row[i] + t * (row[i + 1] - row[i]);
    };
    const auto lerp_r = [&](const std::vector<float>& table) {
        return at(table, r.index) + r.frac * (at(table, r.index + 1) - at(table, r.index));
    };
    return f0 * lerp_r(a_) + lerp_r(b_);
}

float GgxAlbedo::Average(Roughness r, float f0) const {
    const auto lerp_r = [&](const std::vector<float>& v) {
        const size_t j = size_t(r.index);
        return v[j] + r.frac * (v[j + 1] - v[j]);
    };
    return f0 * lerp_r(a_average_) + lerp_r(b_average_);
}

}  // namespace lf
