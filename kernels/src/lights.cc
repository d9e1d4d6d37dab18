#include "lf/kernels/lights.h"

#include <algorithm>
#include <numbers>

namespace lf {

namespace {
constexpr float kPi = std::numbers::pi_v<float>;

// Power over the three channels; the average, not luminance, so a pure blue light counts.
float PowerWeight(const Rgb& c) { return c.Average(); }
}  // namespace

LightSampler::LightSampler(const EmbreeScene& es) : scene_(es) {
    const Scene& scene = es.scene();
    std::vector<double> weights;
    triangle_light_.resize(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const TriangleMesh& mesh = scene.meshes[m];
        triangle_light_[m].assign(mesh.triangles.size(), -1);
        const Material& mat = scene.materials[size_t(mesh.material)];
        if (!mat.IsEmissive()) continue;
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            Vec3 p0, p1, p2;
            es.Triangle(int(m), int(t), &p0, &p1, &p2);
            const float area = 0.5f * Length(Cross(p1 - p0, p2 - p0));
            if (!(area > 0)) continue;
            triangle_light_[m][t] = int(lights_.size());
            lights_.push_back({Kind::kTriangle, int(m), int(t), area});
            weights.push_back(double(kPi) * area * PowerWeight(mat.emission));
        }
    }
    sphere_light_.assign(scene.spheres.size(), -1);
    for (size_t s = 0; s < scene.spheres.size(); ++s) {
        const Material& mat = scene.materials[size_t(scene.spheres[s].material)];
        if (!mat.IsEmissive()) continue;
        const double r = scene.spheres[s].radius;
        const float area = float(4 * std::numbers::pi * r * r);
        sphere_light_[s] = int(lights_.size());
        lights_.push_back({Kind::kSphere, int(s), 0, area});
        weights.push_back(double(kPi) * area * PowerWeight(mat.emission));
    }
    for (size_t i = 0; i < scene.point_lights.size(); ++i) {
        lights_.push_back({Kind::kPoint, int(i), 0, 0});
        weights.push_back(4 * std::numbers::pi * PowerWeight(scene.point_lights[i].intensity));
    }
    double total = 0;
    for (double w : weights) total += w;
    cdf_.resize(weights.size());
    pmf_.resize(weights.size());
    double acc = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        const double p = total > 0 ? weights[i] / total : 1.0 / double(weights.size());
        acc += p;
        pmf_[i] = float(p);
        cdf_[i] = float(acc);
    }
    if (!cdf_.empty()) cdf_.back() = 1.0f;
}

std::optional<LightSample> LightSampler::Sample(const Vec3& ref, float u_pick,
                                                const Vec2& u) const {
    if (lights_.empty()) return std::nullopt;
    const int index = int(std::upper_bound(cdf_.begin(), cdf_.end(), u_pick) - cdf_.begin());
    const int li = std::min(index, int(lights_.size()) - 1);
    const float pick = pmf_[size_t(li)];
    if (!(pick > 0)) return std::nullopt;
    const Light& light = lights_[size_t(li)];
    const Scene& scene = scene_.scene();

    LightSample ls;
    if (light.kind == Kind::kPoint) {
        const PointLight& pl = scene.point_lights[size_t(light.index)];
        ls.point.p = Vec3(pl.position - scene_.origin());
        const Vec3 d = ls.point.p - ref;
        const float dist2 = LengthSquared(d);
        if (!(dist2 > 0)) return std::nullopt;
        ls.wi = d / std::sqrt(dist2);
        ls.radiance = pl.intensity / dist2;
        ls.pdf = pick;
        ls.delta = true;
        return ls;
    }
    Rgb emission;
    if (light.kind == Kind::kTriangle) {
        // Uniform on the triangle (Osada et al. square-root parameterisation).
        const float su = std::sqrt(u.x);
        ls.point = scene_.TrianglePoint(light.index, light.primitive, su * (1 - u.y), su * u.y);
        emission = scene.materials[size_t(scene.meshes[size_t(light.index)].material)].emission;
    } else {
        const float z = 1 - 2 * u.x;
        const float r = std::sqrt(std::max(0.0f, 1 - z * z));
        const float phi = 2 * kPi * u.y;
        ls.point = scene_.SpherePoint(light.index, Vec3(r * std::cos(phi), r * std::sin(phi), z));
        emission = scene.materials[size_t(scene.spheres[size_t(light.index)].material)].emission;
    }
    const Vec3 d = ls.point.p - ref;
    const float dist2 = LengthSquared(d);
    if (!(dist2 > 0)) return std::nullopt;
    ls.wi = d / std::sqrt(dist2);
    const float cos_light = -Dot(ls.point.n, ls.wi);
    if (cos_light <= 0) return std::nullopt;  // emission leaves the front face only
    ls.radiance = emission;
    ls.pdf = pick * dist2 / (cos_light * light.area);
    return ls;
}

int LightSampler::LightIndex(const SurfaceHit& hit) const {
    if (hit.sphere >= 0) return sphere_light_[size_t(hit.sphere)];
    return triangle_light_[size_t(hit.mesh)][size_t(hit.primitive)];
}

float LightSampler::Pdf(const Vec3& ref, const SurfaceHit& hit) const {
    const int li = LightIndex(hit);
    if (li < 0) return 0;
    const Vec3 d = hit.p - ref;
    const float dist2 = LengthSquared(d);
    const float cos_light = std::abs(Dot(hit.n, d)) / std::sqrt(dist2);
    if (!(cos_light > 0)) return 0;
    return pmf_[size_t(li)] * dist2 / (cos_light * lights_[size_t(li)].area);
}

}  // namespace lf
