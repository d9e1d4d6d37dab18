#include "lf/kernels/light_list.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lf/kernels/shading.h"

namespace lf {

std::vector<std::vector<int>> NoTriangleLights(const Scene& scene) {
    std::vector<std::vector<int>> lights(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        lights[m].assign(scene.meshes[m].triangles.size(), -1);
    }
    return lights;
}

std::optional<SphereEmitter> EmissiveSphere(const Scene& scene, size_t s) {
    const Material& mat = scene.materials[size_t(scene.spheres[s].material)];
    if (!mat.IsEmissive()) return std::nullopt;
    const double r = scene.spheres[s].radius;
    return SphereEmitter{float(4 * std::numbers::pi * r * r), EmitsFromBack(mat)};
}

double OneMinusCos(double angle) {
    const double s = std::sin(angle / 2);
    return 2 * s * s;
}

SpotBand SpotBandOf(const SpotLight& spot) {
    const double outer = std::max(OneMinusCos(spot.outer_cone), 1e-12);
    return {outer, std::max(outer - OneMinusCos(spot.inner_cone), 1e-6 * outer)};
}

double SpotFalloffSolidAngle(const SpotLight& spot) {
    const SpotBand band = SpotBandOf(spot);
    const double mean = spot.falloff == SpotLight::Falloff::kSmoothstep ? 0.5 : 1.0 / 3;
    return 2 * std::numbers::pi * (band.outer - band.width + band.width * mean);
}

std::optional<SunDisk> SunDiskOf(const DirectionalLight& dl) {
    // E = L pi sin^2(alpha) for a disk of half-angle alpha facing the surface.
    const double alpha = dl.angular_diameter / 2;
    const double sin_alpha = std::sin(alpha);
    const SunDisk sun{-Vec3(Normalize(dl.direction)), float(OneMinusCos(alpha)),
                      dl.irradiance * float(1 / (std::numbers::pi * sin_alpha * sin_alpha))};
    if (alpha > 0 && sun.one_minus_cos > 0 && std::isfinite(sun.radiance.MaxComponent()) &&
        std::isfinite(1 / (2 * std::numbers::pi_v<float> * sun.one_minus_cos))) {
        return sun;
    }
    return std::nullopt;
}

LightPickTable LightPickTable::FromWeights(const std::vector<double>& weights) {
    double total = 0;
    for (double w : weights) total += w;
    LightPickTable table;
    table.pmf.resize(weights.size());
    table.cdf.resize(weights.size());
    double acc = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        const double p = total > 0 ? weights[i] / total : 1.0 / double(weights.size());
        acc += p;
        table.pmf[i] = float(p);
        table.cdf[i] = float(acc);
    }
    if (!table.cdf.empty()) table.cdf.back() = 1.0f;
    return table;
}

int LightPickTable::Pick(float u) const {
    const int index = int(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin());
    return std::min(index, int(cdf.size()) - 1);
}

}  // namespace lf
