#include "lf/kernels/light_emission.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lf/core/disk_sampling.h"
#include "lf/kernels/bsdf_sampling.h"
#include "lf/kernels/light_list.h"
#include "lf/kernels/shading.h"

namespace lf {

namespace {
constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

// A direction at 1 - cos(theta) = omc from `axis`, azimuth 2 pi u.
Vec3 ConeDirection(const Vec3& axis, float omc, float u) {
    const float sin_theta = std::sqrt(std::max(0.0f, omc * (2 - omc)));
    const float phi = 2 * kPi * u;
    const Frame frame = Frame::FromNormal(axis);
    return Normalize(
        frame.FromLocal(Vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), 1 - omc)));
}

// 1 - cos of the angle between unit vectors a and b, as |a - b|^2 / 2: exact for small angles.
float OneMinusCosBetween(const Vec3& a, const Vec3& b) { return 0.5f * LengthSquared(a - b); }
}  // namespace

EmissionSampler::EmissionSampler(const EmbreeScene& es) : scene_(es) {
    const Scene& scene = es.scene();
    std::vector<double> weights;
    triangle_light_ = NoTriangleLights(scene);
    ForEachEmissiveTriangle(es, [&](const EmissiveTriangle& tri) {
        triangle_light_[size_t(tri.mesh)][size_t(tri.primitive)] = int(lights_.size());
        lights_.push_back({Kind::kTriangle, tri.mesh, tri.primitive, tri.area, tri.two_sided});
        weights.push_back(AreaLightWeight(tri.area, tri.material->emission, tri.two_sided));
        return 1;
    });
    sphere_light_.assign(scene.spheres.size(), -1);
    for (size_t s = 0; s < scene.spheres.size(); ++s) {
        const std::optional<SphereEmitter> sphere = EmissiveSphere(scene, s);
        if (!sphere) continue;
        sphere_light_[s] = int(lights_.size());
        lights_.push_back({Kind::kSphere, int(s), 0, sphere->area, sphere->two_sided});
        weights.push_back(AreaLightWeight(
            sphere->area, scene.materials[size_t(scene.spheres[s].material)].emission,
            sphere->two_sided));
    }
    for (size_t i = 0; i < scene.point_lights.size(); ++i) {
        point_light_.push_back(int(lights_.size()));
        lights_.push_back({Kind::kPoint, int(i), 0, 0, false});
        weights.push_back(4 * std::numbers::pi * LightPowerWeight(scene.point_lights[i].intensity));
    }
    for (size_t i = 0; i < scene.spot_lights.size(); ++i) {
        const SpotLight& spot = scene.spot_lights[i];
        // The cone sizes as LightSampler clamps them, so both see one falloff.
        const SpotBand band = SpotBandOf(spot);
        spots_.push_back({float(band.outer), float(1 / band.width),
                          spot.falloff == SpotLight::Falloff::kSmoothstep, spot.intensity});
        spot_light_.push_back(int(lights_.size()));
        lights_.push_back({Kind::kSpot, int(i), 0, 0, false});
        weights.push_back(SpotFalloffSolidAngle(spot) * LightPowerWeight(spot.intensity));
    }
    const auto [lo, hi] = scene.Bounds();
    const float radius = float(Length(hi - lo) / 2);
    // A scene without geometry still gets a disk for its lights at infinity.
    scene_radius_ = radius > 0 && std::isfinite(radius) ? radius : 1.0f;
    const double cross_section = std::numbers::pi * double(scene_radius_) * scene_radius_;
    for (size_t i = 0; i < scene.directional_lights.size(); ++i) {
        const DirectionalLight& dl = scene.directional_lights[i];
        // The same sun disk, and the same fallback to a delta light, as LightSampler's.
        directional_light_.push_back(int(lights_.size()));
        if (const std::optional<SunDisk> sun = SunDiskOf(dl)) {
            lights_.push_back({Kind::kSun, int(suns_.size()), 0, 0, false});
            suns_.push_back(*sun);
            // The flux through the disk: pi R^2 times the radiance integrated over the cone.
            weights.push_back(cross_section * 2 * std::numbers::pi * sun->one_minus_cos *
                              LightPowerWeight(sun->radiance));
        } else {
            lights_.push_back({Kind::kDirectional, int(i), 0, 0, false});
            weights.push_back(cross_section * LightPowerWeight(dl.irradiance));
        }
    }
    if (scene.environment) {
        environment_.emplace(*scene.environment);
        lights_.push_back({Kind::kEnvironment, 0, 0, 0, false});
        weights.push_back(cross_section * 4 * std::numbers::pi *
                          LightPowerWeight(environment_->MeanRadiance()));
    }
    picks_ = LightPickTable::FromWeights(weights);
}

SurfacePoint EmissionSampler::AreaPoint(const Light& light, const Vec2& u, float time) const {
    if (light.kind == Kind::kTriangle) {
        // Uniform on the triangle (Osada et al.'s square-root parameterisation).
        const float su = std::sqrt(u.x);
        return scene_.TrianglePoint(light.index, light.primitive, su * (1 - u.y), su * u.y, time);
    }
    const float z = 1 - 2 * u.x;
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    const float phi = 2 * kPi * u.y;
    return scene_.SpherePoint(light.index, Vec3(r * std::cos(phi), r * std::sin(phi), z), time);
}

float EmissionSampler::AreaAt(const Light& light, float time) const {
    // A deforming triangle's area changes with time; a still one's is the one of the list.
    if (light.kind == Kind::kTriangle && scene_.Moves(light.index)) {
        return scene_.TriangleArea(light.index, light.primitive, time);
    }
    return light.area;
}

Rgb EmissionSampler::AreaEmission(const Light& light, const SurfacePoint& point) const {
    const Scene& scene = scene_.scene();
    const int material = light.kind == Kind::kTriangle
                             ? scene.meshes[size_t(light.index)].material
                             : scene.spheres[size_t(light.index)].material;
    return EmissionAt(scene_, point, scene.materials[size_t(material)].emission);
}

std::optional<EmissionSample> EmissionSampler::Sample(float u_pick, const Vec2& u_pos,
                                                      const Vec2& u_dir, float time) const {
    if (lights_.empty()) return std::nullopt;
    const int li = picks_.Pick(u_pick);
    EmissionSample es;
    es.light = li;
    es.pick = picks_.pmf[size_t(li)];
    if (!(es.pick > 0)) return std::nullopt;
    const Light& light = lights_[size_t(li)];
    const Scene& scene = scene_.scene();

    switch (light.kind) {
        case Kind::kTriangle:
        case Kind::kSphere: {
            es.point = AreaPoint(light, u_pos, time);
            es.on_surface = true;
            if (light.kind == Kind::kSphere) es.sphere = light.index;
            es.pdf_pos = 1 / AreaAt(light, time);
            Vec2 u = u_dir;
            Vec3 n = es.point.n;
            float side = 1;
            if (light.two_sided) {
                // u.x picks the side and is stretched back over [0, 1).
                if (u.x < 0.5f) {
                    u.x = std::min(2 * u.x, kOneMinusEpsilon);
                } else {
                    u.x = std::min(2 * (u.x - 0.5f), kOneMinusEpsilon);
                    n = -n;
                }
                side = 0.5f;
            }
            const Vec3 local = SampleCosineHemisphere(u);
            if (!(local.z > 0)) return std::nullopt;
            es.w = Normalize(Frame::FromNormal(n).FromLocal(local));
            es.pdf_dir = side * local.z / kPi;
            es.le = AreaEmission(light, es.point);
            break;
        }
        case Kind::kPoint: {
            es.point.p = scene_.PointLightPosition(light.index, time);
            es.delta_pos = true;
            es.pdf_pos = 1;
            const float z = 1 - 2 * u_dir.x;
            const float r = std::sqrt(std::max(0.0f, 1 - z * z));
            const float phi = 2 * kPi * u_dir.y;
            es.w = Vec3(r * std::cos(phi), r * std::sin(phi), z);
            es.point.n = es.w;
            es.pdf_dir = 1 / (4 * kPi);
            es.le = scene.point_lights[size_t(light.index)].intensity;
            break;
        }
        case Kind::kSpot: {
            const SpotCone& cone = spots_[size_t(light.index)];
            const EmbreeScene::SpotPlace place = scene_.SpotLightAt(light.index, time);
            es.point.p = place.position;
            es.delta_pos = true;
            es.pdf_pos = 1;
            // Uniform in the outer cone: 1 - cos(theta) uniform in [0, 1 - cos outer].
            const float omc = u_dir.x * cone.one_minus_cos_outer;
            es.w = ConeDirection(place.direction, omc, u_dir.y);
            es.point.n = es.w;
            es.pdf_dir = 1 / (2 * kPi * cone.one_minus_cos_outer);
            const float t =
                std::clamp((cone.one_minus_cos_outer - omc) * cone.inv_width, 0.0f, 1.0f);
            es.le = cone.intensity * SpotBandFalloff(t, cone.smooth);
            break;
        }
        case Kind::kDirectional:
        case Kind::kSun:
        case Kind::kEnvironment: {
            Vec3 wi;  // towards the light
            if (light.kind == Kind::kDirectional) {
                const DirectionalLight& dl = scene.directional_lights[size_t(light.index)];
                wi = -Vec3(Normalize(dl.direction));
                es.delta_dir = true;
                es.pdf_dir = 1;
                es.le = dl.irradiance;
            } else if (light.kind == Kind::kSun) {
                const SunDisk& sun = suns_[size_t(light.index)];
                wi = ConeDirection(sun.axis, u_dir.x * sun.one_minus_cos, u_dir.y);
                es.pdf_dir = 1 / (2 * kPi * sun.one_minus_cos);
                es.le = sun.radiance;
            } else {
                const std::optional<EnvironmentEmitter::DirectionSample> ds =
                    environment_->Sample(u_dir);
                if (!ds) return std::nullopt;
                wi = ds->wi;
                es.pdf_dir = ds->pdf;
                es.le = ds->radiance;
            }
            // The disk perpendicular to wi, tangent to the bounding sphere on the light's side.
            const Frame frame = Frame::FromNormal(wi);
            const Vec2 d = SampleUniformDiskConcentric(u_pos);
            es.point.p = (wi + frame.s * d.x + frame.t * d.y) * scene_radius_;
            es.w = -wi;
            es.point.n = es.w;
            es.pdf_pos = 1 / (kPi * scene_radius_ * scene_radius_);
            break;
        }
    }
    if (!(es.pdf_pos > 0 && es.pdf_dir > 0) || es.le.IsBlack()) return std::nullopt;
    es.point.time = time;
    return es;
}

int EmissionSampler::LightOf(const SurfaceHit& hit) const {
    if (hit.sphere >= 0) return sphere_light_[size_t(hit.sphere)];
    if (hit.mesh < 0) return -1;
    return triangle_light_[size_t(hit.mesh)][size_t(hit.primitive)];
}

int EmissionSampler::LightOf(const LightSample& sample) const {
    if (sample.sphere >= 0) return sphere_light_[size_t(sample.sphere)];
    if (sample.point_light >= 0) return point_light_[size_t(sample.point_light)];
    if (sample.spot_light >= 0) return spot_light_[size_t(sample.spot_light)];
    if (sample.directional_light >= 0) return directional_light_[size_t(sample.directional_light)];
    if (sample.point.mesh < 0) return -1;
    return triangle_light_[size_t(sample.point.mesh)][size_t(sample.point.primitive)];
}

float EmissionSampler::InfiniteDirPdf(const Light& light, const Vec3& w) const {
    const Vec3 wi = -w;
    switch (light.kind) {
        case Kind::kDirectional: {
            const DirectionalLight& dl = scene_.scene().directional_lights[size_t(light.index)];
            return wi == -Vec3(Normalize(dl.direction)) ? 1.0f : 0.0f;
        }
        case Kind::kSun: {
            const SunDisk& sun = suns_[size_t(light.index)];
            return sun.Contains(wi) ? 1 / (2 * kPi * sun.one_minus_cos) : 0.0f;
        }
        case Kind::kEnvironment:
            return environment_->Pdf(wi);
        default:
            return 0;
    }
}

EmissionPdf EmissionSampler::PdfLe(int li, const Vec3& p, const Vec3& n, const Vec3& w,
                                   float time) const {
    (void)p;  // uniform by area: the density does not depend on where on the light
    const Light& light = lights_[size_t(li)];
    switch (light.kind) {
        case Kind::kTriangle:
        case Kind::kSphere: {
            const float cos = Dot(n, w);
            const float pdf_pos = 1 / AreaAt(light, time);
            if (!light.two_sided && !(cos > 0)) return {pdf_pos, 0};
            return {pdf_pos, std::abs(cos) / kPi * (light.two_sided ? 0.5f : 1.0f)};
        }
        case Kind::kPoint:
            return {1, 1 / (4 * kPi)};
        case Kind::kSpot: {
            const SpotCone& cone = spots_[size_t(light.index)];
            const bool inside =
                OneMinusCosBetween(w, scene_.SpotLightAt(light.index, time).direction) <=
                cone.one_minus_cos_outer;
            return {1, inside ? 1 / (2 * kPi * cone.one_minus_cos_outer) : 0.0f};
        }
        default:
            return {1 / (kPi * scene_radius_ * scene_radius_), InfiniteDirPdf(light, w)};
    }
}

EmissionPdf EmissionSampler::EscapedPdfLe(const Vec3& w) const {
    EmissionPdf pdf{1 / (kPi * scene_radius_ * scene_radius_), 0};
    for (size_t i = 0; i < lights_.size(); ++i) {
        const Kind kind = lights_[i].kind;
        if (kind == Kind::kSun || kind == Kind::kEnvironment) {
            pdf.dir += picks_.pmf[i] * InfiniteDirPdf(lights_[i], -w);
        }
    }
    return pdf;
}

}  // namespace lf
