#include "lf/kernels/lights.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lf {

namespace {
constexpr float kPi = std::numbers::pi_v<float>;

// Power over the three channels; the average, not luminance, so a pure blue light counts.
float PowerWeight(const Rgb& c) { return c.Average(); }

// KHR_lights_punctual's recommended spot falloff as a linear map of the cosine to the axis,
// clamped and squared: 0 outside the outer cone, 1 inside the inner.
float ConeScale(const SpotLight& spot) {
    return 1 / std::max(0.001f, float(std::cos(spot.inner_cone) - std::cos(spot.outer_cone)));
}
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
    for (size_t i = 0; i < scene.spot_lights.size(); ++i) {
        const SpotLight& spot = scene.spot_lights[i];
        const float scale = ConeScale(spot);
        spot_cones_.push_back(
            {Vec3(Normalize(spot.direction)), scale, -float(std::cos(spot.outer_cone)) * scale});
        lights_.push_back({Kind::kSpot, int(i), 0, 0});
        // The solid angle of the cone halfway through the falloff.
        const double half_angle = (spot.inner_cone + spot.outer_cone) / 2;
        weights.push_back(2 * std::numbers::pi * (1 - std::cos(half_angle)) *
                          PowerWeight(spot.intensity));
    }
    const auto [lo, hi] = scene.Bounds();
    scene_radius_ = float(Length(hi - lo) / 2);
    for (size_t i = 0; i < scene.directional_lights.size(); ++i) {
        lights_.push_back({Kind::kDirectional, int(i), 0, 0});
        // What falls on the scene's bounding sphere's cross-section.
        weights.push_back(std::numbers::pi * double(scene_radius_) * scene_radius_ *
                          PowerWeight(scene.directional_lights[i].irradiance));
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

    if (light.kind == Kind::kPoint || light.kind == Kind::kSpot ||
        light.kind == Kind::kDirectional) {
        std::optional<LightSample> ls = SampleDelta(light, ref);
        if (ls) ls->pdf = pick;
        return ls;
    }
    LightSample ls;
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

std::optional<LightSample> LightSampler::SampleDelta(const Light& light, const Vec3& ref) const {
    const Scene& scene = scene_.scene();
    LightSample ls;
    ls.delta = true;
    if (light.kind == Kind::kDirectional) {
        const DirectionalLight& dl = scene.directional_lights[size_t(light.index)];
        ls.wi = -Vec3(Normalize(dl.direction));
        // Beyond the bounding sphere from any point inside it (and at least one unit away when
        // the scene has no extent).
        ls.point.p = ref + ls.wi * (2 * scene_radius_ + Length(ref) + 1);
        ls.point.n = -ls.wi;
        ls.radiance = dl.irradiance;
        return ls;
    }
    const bool spot = light.kind == Kind::kSpot;
    const Vec3d position = spot ? scene.spot_lights[size_t(light.index)].position
                                : scene.point_lights[size_t(light.index)].position;
    ls.point.p = Vec3(position - scene_.origin());
    const Vec3 d = ls.point.p - ref;
    const float dist2 = LengthSquared(d);
    if (!(dist2 > 0)) return std::nullopt;
    ls.wi = d / std::sqrt(dist2);
    ls.point.n = -ls.wi;
    if (!spot) {
        ls.radiance = scene.point_lights[size_t(light.index)].intensity / dist2;
        return ls;
    }
    const SpotCone& cone = spot_cones_[size_t(light.index)];
    const float a = std::clamp(-Dot(cone.direction, ls.wi) * cone.scale + cone.offset, 0.0f, 1.0f);
    if (a == 0) return std::nullopt;  // outside the outer cone: no shadow ray needed
    ls.radiance = scene.spot_lights[size_t(light.index)].intensity * (a * a / dist2);
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
