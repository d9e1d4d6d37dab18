#include "lf/kernels/sheen_lobe.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lf/kernels/bsdf_sampling.h"
#include "tbb/parallel_for.h"
#include "tbb/task_arena.h"

namespace lf {
namespace {

constexpr float kInvPi = std::numbers::inv_pi_v<float>;

// Below this the lobe is a sliver at grazing half vectors that float cannot resolve.
constexpr float kMinAlpha = 1e-4f;

// The albedo table: mu nodes crowd towards grazing (mu = s^2), roughness nodes are uniform in r.
constexpr int kMuSize = 32;
constexpr int kRoughnessSize = 48;
// Midpoint grid of cosine-weighted directions per entry: within 2e-3 plus 3% of a 512 x 512
// reference for r >= 0.2 (Sheen test), built in about 0.3 s of one core.
constexpr int kQuadrature = 64;

float Clamp01(float x) { return x > 0 ? std::min(x, 1.0f) : 0.0f; }  // NaN -> 0

float MuAt(int i) {
    const float s = float(i) / (kMuSize - 1);
    return s * s;
}

// The extension's fit of the Charlie Lambda, ln Lambda for cos theta below 1/2.
float LambdaFit(float x, float alpha) {
    const float t = (1 - alpha) * (1 - alpha);
    const float a = std::lerp(21.5473f, 25.3245f, t);
    const float b = std::lerp(3.82987f, 3.32435f, t);
    const float c = std::lerp(0.19823f, 0.16801f, t);
    const float d = std::lerp(-1.97760f, -1.27393f, t);
    const float e = std::lerp(-4.32054f, -4.85967f, t);
    return a / (1 + b * std::pow(x, c)) + d * x + e;
}

float Lambda(float cos, float alpha) {
    if (cos < 0.5f) return std::exp(LambdaFit(cos, alpha));
    return std::exp(2 * LambdaFit(0.5f, alpha) - LambdaFit(1 - cos, alpha));
}

struct Table {
    std::vector<float> e = std::vector<float>(size_t(kMuSize * kRoughnessSize));
    Table() {
        // Isolated: the first use may come from inside a render's parallel loop (as GgxAlbedo).
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(0, kRoughnessSize, [&](int j) {
                const float r = float(j) / (kRoughnessSize - 1);
                for (int i = 0; i < kMuSize; ++i) {
                    e[size_t(j * kMuSize + i)] =
                        float(SheenLobe::IntegrateAlbedo(std::max(MuAt(i), 1e-4f), r, kQuadrature));
                }
            });
        });
    }
};

const Table& GetTable() {
    static const Table table;
    return table;
}

}  // namespace

SheenLobe::SheenLobe(const Rgb& color, float roughness)
    : color_(Clamp01(color.r), Clamp01(color.g), Clamp01(color.b)),
      max_color_(std::max({color_.r, color_.g, color_.b})),
      roughness_(Clamp01(roughness)),
      alpha_(std::max(roughness_ * roughness_, kMinAlpha)) {}

float SheenLobe::Value(const Vec3& wo, const Vec3& wi, float alpha) {
    const Vec3 wm = Normalize(wo + wi);
    const float sin2 = std::max(0.0f, 1 - wm.z * wm.z);
    const float d = (2 + 1 / alpha) * std::pow(sin2, 0.5f / alpha) * (0.5f * kInvPi);
    const float v = 1 / ((1 + Lambda(wo.z, alpha) + Lambda(wi.z, alpha)) * (4 * wo.z * wi.z));
    return d * std::clamp(v, 0.0f, 1.0f);
}

Rgb SheenLobe::Eval(const Vec3& wo, const Vec3& wi) const {
    // The extension's visibility is no exact shadowing term: on smooth sheens at grazing angles
    // the lobe alone reflects up to 1.5 times what arrives. Dividing by the larger of the two
    // albedos where it exceeds 1 keeps it reciprocal and within the furnace.
    const float excess =
        std::max({1.0f, TabulatedAlbedo(wo.z, roughness_), TabulatedAlbedo(wi.z, roughness_)});
    return color_ * (Value(wo, wi, alpha_) / excess);
}

float SheenLobe::Pdf(const Vec3& wi) { return wi.z > 0 ? wi.z * kInvPi : 0; }

Vec3 SheenLobe::Sample(const Vec2& u) { return SampleCosineHemisphere(u); }

double SheenLobe::IntegrateAlbedo(float mu, float roughness, int quadrature) {
    const double alpha = std::max(roughness * roughness, kMinAlpha);
    const Vec3 wo(std::sqrt(1 - mu * mu), 0, mu);
    // Half vectors distributed as D(h) cos(theta_h), where smooth sheens put all their weight
    // (near the horizon): sin(theta_h) = u^(1 / (2 + 1/a)). The reflection's density is
    // D cos(theta_h) / (4 wo.h), so each point weighs f cos_i 4 wo.h / (D cos(theta_h)).
    const double exponent = 1 / (2 + 1 / alpha);
    double sum = 0;
    for (int y = 0; y < quadrature; ++y) {
        for (int x = 0; x < quadrature; ++x) {
            const double sin_h = std::pow((x + 0.5) / quadrature, exponent);
            const double cos_h = std::sqrt(std::max(0.0, 1 - sin_h * sin_h));
            const double phi = 2 * std::numbers::pi * (y + 0.5) / quadrature;
            const Vec3 h(float(sin_h * std::cos(phi)), float(sin_h * std::sin(phi)), float(cos_h));
            const float cos_oh = Dot(wo, h);
            if (cos_oh <= 0 || cos_h <= 0) continue;
            const Vec3 wi = h * (2 * cos_oh) - wo;
            if (wi.z <= 0) continue;
            const double d = (2 + 1 / alpha) * std::pow(sin_h, 1 / alpha) / (2 * std::numbers::pi);
            if (!(d > 0)) continue;
            sum += Value(wo, wi, float(alpha)) * wi.z * 4 * cos_oh / (d * cos_h);
        }
    }
    return sum / (double(quadrature) * quadrature);
}

float SheenLobe::TabulatedAlbedo(float mu, float roughness) {
    const Table& t = GetTable();
    const float s = std::sqrt(std::clamp(mu, 0.0f, 1.0f)) * (kMuSize - 1);
    const int i = std::min(int(s), kMuSize - 2);
    const float fi = s - float(i);
    const float q = Clamp01(roughness) * (kRoughnessSize - 1);
    const int j = std::min(int(q), kRoughnessSize - 2);
    const float fj = q - float(j);
    const auto at = [&](int jj, int ii) { return t.e[size_t(jj * kMuSize + ii)]; };
    const float lo = std::lerp(at(j, i), at(j, i + 1), fi);
    const float hi = std::lerp(at(j + 1, i), at(j + 1, i + 1), fi);
    return std::lerp(lo, hi, fj);
}

float SheenLobe::Albedo(const Vec3& w) const {
    return max_color_ > 0 ? max_color_ * std::min(TabulatedAlbedo(w.z, roughness_), 1.0f) : 0;
}

float SheenLobe::Keep(const Vec3& wo, const Vec3& wi) const {
    return 1 - std::max(Albedo(wo), Albedo(wi));
}

}  // namespace lf
