#include "lf/kernels/lights.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lf/kernels/shading.h"

namespace lf {

namespace {
constexpr float kPi = std::numbers::pi_v<float>;

// Power over the three channels; the average, not luminance, so a pure blue light counts.
float PowerWeight(const Rgb& c) { return c.Average(); }

// 1 - cos(angle), exact also for angles so small that cos rounds to 1.
double OneMinusCos(double angle) {
    const double s = std::sin(angle / 2);
    return 2 * s * s;
}

// A spot light's cone sizes as 1 - cos: the outer cone's, at least 1e-12 so that a cone of
// under a microradian still has a float extent, and the falloff band's width from there
// towards the axis, at least a millionth of the cone so that its slope stays finite when the
// cones (nearly) coincide.
struct SpotBand {
    double outer, width;
};
SpotBand Band(const SpotLight& spot) {
    const double outer = std::max(OneMinusCos(spot.outer_cone), 1e-12);
    return {outer, std::max(outer - OneMinusCos(spot.inner_cone), 1e-6 * outer)};
}

// The falloff as a function of t = (cos - cos outer) / width in [0, 1].
float Falloff(float t, bool smooth) { return smooth ? t * t * (3 - 2 * t) : t * t; }

// The solid angle a spot light's falloff integrates to: 2 pi times the integral of the falloff
// over cos in [-1, 1], which is 1 inside the band (1 - cos below outer - width) and the mean of
// t^2 (1/3) or of the smoothstep (1/2) over the band: positive for any cones.
double SpotSolidAngle(const SpotLight& spot) {
    const SpotBand band = Band(spot);
    const double mean = spot.falloff == SpotLight::Falloff::kSmoothstep ? 0.5 : 1.0 / 3;
    return 2 * std::numbers::pi * (band.outer - band.width + band.width * mean);
}
}  // namespace

bool LightSampler::SunDisk::Contains(const Vec3& w) const {
    // |w - axis|^2 = 2 (1 - cos): exact for small angles, where cos itself rounds to 1.
    return LengthSquared(w - axis) <= 2 * one_minus_cos;
}

LightSampler::LightSampler(const EmbreeScene& es) : scene_(es) {
    const Scene& scene = es.scene();
    std::vector<double> weights;
    triangle_light_.resize(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const TriangleMesh& mesh = scene.meshes[m];
        triangle_light_[m].assign(mesh.triangles.size(), -1);
        const Material& mat = scene.materials[size_t(mesh.material)];
        if (!mat.IsEmissive()) continue;
        const bool two_sided = EmitsFromBack(mat);
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            Vec3 p0, p1, p2;
            es.Triangle(int(m), int(t), &p0, &p1, &p2);
            const float area = 0.5f * Length(Cross(p1 - p0, p2 - p0));
            if (!(area > 0)) continue;
            triangle_light_[m][t] = int(lights_.size());
            lights_.push_back({Kind::kTriangle, int(m), int(t), area, two_sided});
            weights.push_back(double(kPi) * area * PowerWeight(mat.emission) * (two_sided ? 2 : 1));
        }
    }
    sphere_light_.assign(scene.spheres.size(), -1);
    for (size_t s = 0; s < scene.spheres.size(); ++s) {
        const Material& mat = scene.materials[size_t(scene.spheres[s].material)];
        if (!mat.IsEmissive()) continue;
        const double r = scene.spheres[s].radius;
        const float area = float(4 * std::numbers::pi * r * r);
        const bool two_sided = EmitsFromBack(mat);
        sphere_light_[s] = int(lights_.size());
        lights_.push_back({Kind::kSphere, int(s), 0, area, two_sided});
        weights.push_back(double(kPi) * area * PowerWeight(mat.emission) * (two_sided ? 2 : 1));
    }
    for (size_t i = 0; i < scene.point_lights.size(); ++i) {
        lights_.push_back({Kind::kPoint, int(i), 0, 0, false});
        weights.push_back(4 * std::numbers::pi * PowerWeight(scene.point_lights[i].intensity));
    }
    for (size_t i = 0; i < scene.spot_lights.size(); ++i) {
        const SpotLight& spot = scene.spot_lights[i];
        const SpotBand band = Band(spot);
        spot_cones_.push_back({Vec3(Normalize(spot.direction)), float(band.outer),
                               float(1 / band.width),
                               spot.falloff == SpotLight::Falloff::kSmoothstep});
        lights_.push_back({Kind::kSpot, int(i), 0, 0, false});
        weights.push_back(SpotSolidAngle(spot) * PowerWeight(spot.intensity));
    }
    const auto [lo, hi] = scene.Bounds();
    scene_radius_ = float(Length(hi - lo) / 2);
    // Lights at infinity: what falls on the scene's bounding sphere's cross-section.
    const double cross_section = std::numbers::pi * double(scene_radius_) * scene_radius_;
    std::vector<size_t> sun_lights;
    for (size_t i = 0; i < scene.directional_lights.size(); ++i) {
        const DirectionalLight& dl = scene.directional_lights[i];
        // E = L pi sin^2(alpha) for a disk of half-angle alpha facing the surface.
        const double alpha = dl.angular_diameter / 2;
        const double sin_alpha = std::sin(alpha), sin_half = std::sin(alpha / 2);
        const SunDisk sun{-Vec3(Normalize(dl.direction)), float(2 * sin_half * sin_half),
                          dl.irradiance * float(1 / (std::numbers::pi * sin_alpha * sin_alpha))};
        // A disk so small that its radiance or density overflows float is the delta light.
        if (alpha > 0 && sun.one_minus_cos > 0 && std::isfinite(sun.radiance.MaxComponent()) &&
            std::isfinite(1 / (2 * kPi * sun.one_minus_cos))) {
            sun_lights.push_back(lights_.size());
            lights_.push_back({Kind::kSun, int(suns_.size()), 0, 0, false});
            suns_.push_back(sun);
        } else {
            lights_.push_back({Kind::kDirectional, int(i), 0, 0, false});
        }
        weights.push_back(cross_section * PowerWeight(dl.irradiance));
    }
    size_t environment_light = 0;
    if (scene.environment) {
        environment_.emplace(*scene.environment);
        environment_light = lights_.size();
        lights_.push_back({Kind::kEnvironment, 0, 0, 0, false});
        // Radiance L from every direction puts pi L on each point of a surface facing it.
        weights.push_back(cross_section * std::numbers::pi *
                          PowerWeight(environment_->MeanRadiance()));
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
    for (size_t light : sun_lights) sun_pmf_.push_back(pmf_[light]);
    if (environment_) environment_pmf_ = pmf_[environment_light];
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
    if (light.kind == Kind::kSun || light.kind == Kind::kEnvironment) {
        // The lights at infinity are weighed as one: a sampled direction carries all their
        // radiance (sky behind a sun, overlapping suns) at the density with which any of them
        // would have produced it, as a BSDF ray escaping the same way is (EscapedRadiance,
        // EscapedPdf), so the two MIS weights sum to 1 wherever they overlap.
        const std::optional<Vec3> wi = SampleInfiniteDirection(light, u);
        if (!wi) return std::nullopt;
        LightSample ls;
        ls.wi = *wi;
        ls.radiance = EscapedRadiance(ls.wi);
        ls.pdf = EscapedPdf(ls.wi);
        if (!(ls.pdf > 0) || ls.radiance.IsBlack()) return std::nullopt;
        ls.point.p = InfinitePoint(ref, ls.wi);
        ls.point.n = -ls.wi;
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
    const float cos_front = -Dot(ls.point.n, ls.wi);
    const float cos_light = light.two_sided ? std::abs(cos_front) : cos_front;
    if (!(cos_light > 0)) return std::nullopt;  // a one-sided emitter seen from behind
    ls.radiance = emission;
    ls.pdf = pick * dist2 / (cos_light * light.area);
    return ls;
}

std::optional<Vec3> LightSampler::SampleInfiniteDirection(const Light& light, const Vec2& u) const {
    if (light.kind == Kind::kSun) {
        // Uniform in the cone: cos(theta) uniform in [cos alpha, 1].
        const SunDisk& sun = suns_[size_t(light.index)];
        const float omc = u.x * sun.one_minus_cos;  // 1 - cos(theta)
        const float sin_theta = std::sqrt(std::max(0.0f, omc * (2 - omc)));
        const float phi = 2 * kPi * u.y;
        const Frame frame = Frame::FromNormal(sun.axis);
        return Normalize(
            frame.FromLocal(Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), 1 - omc)));
    }
    const std::optional<EnvironmentEmitter::DirectionSample> ds = environment_->Sample(u);
    if (!ds) return std::nullopt;
    return ds->wi;
}

Vec3 LightSampler::InfinitePoint(const Vec3& ref, const Vec3& wi) const {
    // Beyond the bounding sphere from any point inside it (and at least one unit away when the
    // scene has no extent).
    return ref + wi * (2 * scene_radius_ + Length(ref) + 1);
}

std::optional<LightSample> LightSampler::SampleDelta(const Light& light, const Vec3& ref) const {
    const Scene& scene = scene_.scene();
    LightSample ls;
    ls.delta = true;
    if (light.kind == Kind::kDirectional) {
        const DirectionalLight& dl = scene.directional_lights[size_t(light.index)];
        ls.wi = -Vec3(Normalize(dl.direction));
        ls.point.p = InfinitePoint(ref, ls.wi);
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
    // 1 - cos of the angle to the axis as |d - axis|^2 / 2 (d = -wi, from the light): exact for
    // narrow cones, where cos itself rounds to 1 in float.
    const float one_minus_cos = 0.5f * LengthSquared(ls.wi + cone.direction);
    const float t =
        std::clamp((cone.one_minus_cos_outer - one_minus_cos) * cone.inv_width, 0.0f, 1.0f);
    if (t == 0) return std::nullopt;  // outside the outer cone: no shadow ray needed
    ls.radiance =
        scene.spot_lights[size_t(light.index)].intensity * (Falloff(t, cone.smooth) / dist2);
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

Rgb LightSampler::EscapedRadiance(const Vec3& w) const {
    Rgb L = environment_ ? environment_->Le(w) : Rgb(0.0f);
    for (const SunDisk& sun : suns_) {
        if (sun.Contains(w)) L += sun.radiance;
    }
    return L;
}

float LightSampler::EscapedPdf(const Vec3& w) const {
    float pdf = environment_ ? environment_pmf_ * environment_->Pdf(w) : 0.0f;
    for (size_t i = 0; i < suns_.size(); ++i) {
        if (suns_[i].Contains(w)) pdf += sun_pmf_[i] / (2 * kPi * suns_[i].one_minus_cos);
    }
    return pdf;
}

}  // namespace lf
