#include "lf/kernels/lights.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "lf/kernels/light_bounds.h"
#include "lf/kernels/light_list.h"
#include "lf/kernels/shading.h"
#include "lf/kernels/sphere_cone_sampling.h"
#include "lf/kernels/spherical_triangle.h"

namespace lf {

namespace {

// The time (Ray::time) of step `step` of the scene's moving geometry and lights.
float StepTime(const EmbreeScene& es, int step) { return float(step) / float(es.steps() - 1); }
constexpr float kPi = std::numbers::pi_v<float>;

// Triangles and rectangles subtending less than this many steradians are sampled by area.
// Solid-angle sampling costs a full path in a Cornell box (64 x 64, Sobol, light_sampling_bench)
// 30-45% more CPU time when used wherever it is well-conditioned (1e-4 sr), for 2-5% less variance
// there (18% with direct light only); from 0.25 sr on it keeps nearly all its gain where it
// matters (a lamp 0.15 from a wall: variance x0.05 at equal spp) and costs the Cornell box
// within noise. docs/rendering.md has the measurements.
constexpr float kMinSampledSolidAngle = 0.25f;

// The largest float below 1, for mapping [0, 1) onto itself after a division.
constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

// pbrt-v4's warp of a spherical triangle's or rectangle's sample space towards the receiver's
// cosine: a bilinear density over [0, 1]^2 whose corners carry |cos| at the points on the emitter
// they map to (at least 0.01 so no part is left unsampled). Uniform sampling in solid angle
// leaves the cosine's variance, which dominates for a large emitter seen at grazing angles.
class CosineWarp {
  public:
    // c00, c10, c01, c11: where u = (0, 0), (1, 0), (0, 1), (1, 1) map to.
    CosineWarp(const Vec3& ref, const Vec3& n, const Vec3& c00, const Vec3& c10, const Vec3& c01,
               const Vec3& c11) {
        const auto weight = [&](const Vec3& v) {
            return std::max(0.01f, std::abs(Dot(n, Normalize(v - ref))));
        };
        w_[0] = weight(c00);
        w_[1] = weight(c10);
        w_[2] = weight(c01);
        w_[3] = weight(c11);
    }
    // For SphericalTriangle(ref, v0, v1, v2): u = (0, y) and (1, 0) map to v1, (0, 1) to v0,
    // (1, 1) to v2.
    static CosineWarp ForTriangle(const Vec3& ref, const Vec3& n, const Vec3& v0, const Vec3& v1,
                                  const Vec3& v2) {
        return CosineWarp(ref, n, v1, v1, v0, v2);
    }
    // For SphericalRectangle(ref, r): u is the point's (s, t) on the rectangle.
    static CosineWarp ForRectangle(const Vec3& ref, const Vec3& n, const RectangleFrame& r) {
        return CosineWarp(ref, n, r.corner, r.corner + r.ex, r.corner + r.ey,
                          r.corner + r.ex + r.ey);
    }

    // u distributed by the bilinear density, for u uniform in [0, 1)^2.
    Vec2 Sample(const Vec2& u) const {
        const float y = SampleLinear(u.y, w_[0] + w_[1], w_[2] + w_[3]);
        return {SampleLinear(u.x, Lerp(y, w_[0], w_[2]), Lerp(y, w_[1], w_[3])), y};
    }
    float Pdf(const Vec2& p) const {
        return 4 *
               ((1 - p.x) * (1 - p.y) * w_[0] + p.x * (1 - p.y) * w_[1] + (1 - p.x) * p.y * w_[2] +
                p.x * p.y * w_[3]) /
               (w_[0] + w_[1] + w_[2] + w_[3]);
    }

  private:
    static float Lerp(float t, float a, float b) { return (1 - t) * a + t * b; }
    // x in [0, 1) with density proportional to Lerp(x, a, b) (a, b > 0).
    static float SampleLinear(float u, float a, float b) {
        const float x = u * (a + b) / (a + std::sqrt(Lerp(u, a * a, b * b)));
        return std::min(x, kOneMinusEpsilon);
    }

    float w_[4];
};

// The dual vectors of a triangle's edges e1 = p1 - p0, e2 = p2 - p0 in its plane: Dot(q - p0,
// dual1) and Dot(q - p0, dual2) are the barycentrics b1, b2 of q.
void DualEdges(const Vec3& p0, const Vec3& p1, const Vec3& p2, Vec3* dual1, Vec3* dual2) {
    const Vec3d e1 = Vec3d(p1) - Vec3d(p0), e2 = Vec3d(p2) - Vec3d(p0);
    const double a = Dot(e1, e1), b = Dot(e1, e2), c = Dot(e2, e2);
    const double det = a * c - b * b;
    *dual1 = Vec3((e1 * c - e2 * b) / det);
    *dual2 = Vec3((e2 * a - e1 * b) / det);
}
}  // namespace

// Triangles `t` and `t + 1` of mesh m form a rectangle when they share an edge (two vertex
// positions), the two other vertices are opposite corners (their sum is the shared ones'), the
// edges at a corner are perpendicular and both triangles face the same way; all to within a
// relative 1e-5, far above float rounding and far below any shape a modeller means as other
// than a rectangle.
std::optional<LightSampler::Rectangle> LightSampler::FormRectangle(const EmbreeScene& es, int m,
                                                                   int t) {
    // A moving mesh's rectangle need not stay one: its triangles are lit one by one.
    if (es.Moves(m)) return std::nullopt;
    std::array<Vec3, 3> a, b;
    es.Triangle(m, t, 0, &a[0], &a[1], &a[2]);
    es.Triangle(m, t + 1, 0, &b[0], &b[1], &b[2]);
    // The vertex of each triangle that the other lacks.
    int a_only = -1, b_only = -1, shared = 0;
    for (int i = 0; i < 3; ++i) {
        const bool in_b = a[size_t(i)] == b[0] || a[size_t(i)] == b[1] || a[size_t(i)] == b[2];
        shared += in_b;
        if (!in_b) a_only = i;
        if (b[size_t(i)] != a[0] && b[size_t(i)] != a[1] && b[size_t(i)] != a[2]) b_only = i;
    }
    if (shared != 2 || a_only < 0 || b_only < 0) return std::nullopt;
    const Vec3 corner = a[size_t(a_only)];
    const Vec3 ex = a[size_t(a_only + 1) % 3] - corner, ey = a[size_t(a_only + 2) % 3] - corner;
    const float lx = Length(ex), ly = Length(ey);
    const float tolerance = 1e-5f * std::max(lx, ly);
    if (!(lx > 0 && ly > 0) || Length(corner + ex + ey - b[size_t(b_only)]) > tolerance ||
        std::abs(Dot(ex, ey)) > tolerance * std::min(lx, ly) ||
        !(Dot(Cross(a[1] - a[0], a[2] - a[0]), Cross(b[1] - b[0], b[2] - b[0])) > 0)) {
        return std::nullopt;
    }
    Rectangle r{RectangleFrame(corner, ex, ey), {}};
    for (int half = 0; half < 2; ++half) {
        const std::array<Vec3, 3>& v = half == 0 ? a : b;
        Rectangle::Half& h = r.halves[half];
        h.primitive = t + half;
        h.origin = v[0];
        DualEdges(v[0], v[1], v[2], &h.dual1, &h.dual2);
    }
    return r;
}

LightSampler::LightSampler(const EmbreeScene& es, LightStrategy strategy)
    : scene_(es), strategy_(strategy) {
    const Scene& scene = es.scene();
    std::vector<double> weights;
    // The finite lights' bounds for the BVH, by light index, in the units of `weights`.
    std::vector<LightBounds> bounds;
    triangle_light_ = NoTriangleLights(scene);
    ForEachEmissiveTriangle(es, [&](const EmissiveTriangle& tri) {
        const int m = tri.mesh, t = tri.primitive;
        const bool two_sided = tri.two_sided;
        const float radiance = LightPowerWeight(tri.material->emission);
        triangle_light_[size_t(m)][size_t(t)] = int(lights_.size());
        std::optional<Rectangle> rectangle;
        if (size_t(t) + 1 < triangle_light_[size_t(m)].size()) {
            rectangle = FormRectangle(es, m, t);
        }
        LightBounds b = TriangleLightBounds(tri.p[0], tri.p[1], tri.p[2], radiance, two_sided);
        // A moving triangle's bounds hold it at every step (and so between them).
        for (int step = 1; es.Moves(m) && step < es.steps(); ++step) {
            Vec3 p0, p1, p2;
            es.Triangle(m, t, StepTime(es, step), &p0, &p1, &p2);
            b = Union(b, TriangleLightBounds(p0, p1, p2, radiance, two_sided));
        }
        if (rectangle) {
            Vec3 q0, q1, q2;
            es.Triangle(m, t + 1, 0, &q0, &q1, &q2);
            b = Union(b, TriangleLightBounds(q0, q1, q2, radiance, two_sided));
            const float rectangle_area = Length(Cross(rectangle->frame.ex, rectangle->frame.ey));
            lights_.push_back(
                {Kind::kRectangle, m, int(rectangles_.size()), rectangle_area, two_sided});
            rectangles_.push_back(*rectangle);
            triangle_light_[size_t(m)][size_t(t) + 1] = triangle_light_[size_t(m)][size_t(t)];
        } else {
            lights_.push_back({Kind::kTriangle, m, t, tri.area, two_sided});
        }
        weights.push_back(AreaLightWeight(lights_.back().area, tri.material->emission, two_sided));
        bounds.push_back(b);
        return rectangle ? 2 : 1;
    });
    sphere_light_.assign(scene.spheres.size(), -1);
    for (size_t s = 0; s < scene.spheres.size(); ++s) {
        const std::optional<SphereEmitter> sphere = EmissiveSphere(scene, s);
        if (!sphere) continue;
        const Rgb& emission = scene.materials[size_t(scene.spheres[s].material)].emission;
        sphere_light_[s] = int(lights_.size());
        lights_.push_back({Kind::kSphere, int(s), 0, sphere->area, sphere->two_sided});
        weights.push_back(AreaLightWeight(sphere->area, emission, sphere->two_sided));
        // Seen from inside, a two-sided sphere's normals still cover every direction.
        const float power = LightPowerWeight(emission) * (sphere->two_sided ? 2 : 1);
        const float radius = float(scene.spheres[s].radius);
        LightBounds b = SphereLightBounds(es.SphereCenter(int(s), 0), radius, power);
        // A moving sphere's bounds hold it at every step (and so between them).
        for (int step = 1; step < es.steps(); ++step) {
            b = Union(
                b, SphereLightBounds(es.SphereCenter(int(s), StepTime(es, step)), radius, power));
        }
        bounds.push_back(b);
    }
    for (size_t i = 0; i < scene.point_lights.size(); ++i) {
        const PointLight& point = scene.point_lights[i];
        lights_.push_back({Kind::kPoint, int(i), 0, 0, false});
        weights.push_back(4 * std::numbers::pi * LightPowerWeight(point.intensity));
        LightBounds b =
            PointLightBounds(es.PointLightPosition(int(i), 0), LightPowerWeight(point.intensity));
        // A moving light's bounds hold it at every step (and so between them).
        for (int step = 1; step < es.steps(); ++step) {
            b = Union(b, PointLightBounds(es.PointLightPosition(int(i), StepTime(es, step)),
                                          LightPowerWeight(point.intensity)));
        }
        bounds.push_back(b);
    }
    for (size_t i = 0; i < scene.spot_lights.size(); ++i) {
        const SpotLight& spot = scene.spot_lights[i];
        const SpotBand band = SpotBandOf(spot);
        spot_cones_.push_back({float(band.outer), float(1 / band.width),
                               spot.falloff == SpotLight::Falloff::kSmoothstep});
        lights_.push_back({Kind::kSpot, int(i), 0, 0, false});
        weights.push_back(SpotFalloffSolidAngle(spot) * LightPowerWeight(spot.intensity));
        // The outer cosine rounded down (a wider cone) so that even a cone whose cosine rounds
        // to 1 in float keeps a positive pick probability wherever it shines.
        const float cos_outer = std::nextafter(float(1 - band.outer), -1.0f);
        const float cos_inner = std::max(float(1 - (band.outer - band.width)), cos_outer);
        const EmbreeScene::SpotPlace place = es.SpotLightAt(int(i), 0);
        LightBounds b = SpotLightBounds(place.position, place.direction,
                                        LightPowerWeight(spot.intensity), cos_inner, cos_outer);
        for (int step = 1; step < es.steps(); ++step) {
            const EmbreeScene::SpotPlace at = es.SpotLightAt(int(i), StepTime(es, step));
            b = Union(b, SpotLightBounds(at.position, at.direction,
                                         LightPowerWeight(spot.intensity), cos_inner, cos_outer));
        }
        bounds.push_back(b);
    }
    finite_count_ = lights_.size();
    const auto [lo, hi] = scene.Bounds();
    scene_radius_ = float(Length(hi - lo) / 2);
    // Lights at infinity: what falls on the scene's bounding sphere's cross-section.
    const double cross_section = std::numbers::pi * double(scene_radius_) * scene_radius_;
    std::vector<size_t> sun_lights;
    for (size_t i = 0; i < scene.directional_lights.size(); ++i) {
        const DirectionalLight& dl = scene.directional_lights[i];
        if (const std::optional<SunDisk> sun = SunDiskOf(dl)) {
            sun_lights.push_back(lights_.size());
            lights_.push_back({Kind::kSun, int(suns_.size()), 0, 0, false});
            suns_.push_back(*sun);
        } else {
            lights_.push_back({Kind::kDirectional, int(i), 0, 0, false});
        }
        weights.push_back(cross_section * LightPowerWeight(dl.irradiance));
    }
    size_t environment_light = 0;
    if (scene.environment) {
        environment_.emplace(*scene.environment);
        environment_light = lights_.size();
        lights_.push_back({Kind::kEnvironment, 0, 0, 0, false});
        // Radiance L from every direction puts pi L on each point of a surface facing it.
        weights.push_back(cross_section * std::numbers::pi *
                          LightPowerWeight(environment_->MeanRadiance()));
    }
    LightPickTable picks = LightPickTable::FromWeights(weights);
    pmf_ = std::move(picks.pmf);
    cdf_ = std::move(picks.cdf);
    // Sample sends u_pick below cdf_[finite_count_ - 1] to the BVH: exactly that probability.
    if (finite_count_ > 0) finite_pmf_ = cdf_[finite_count_ - 1];
    if (strategy_ == LightStrategy::kBvh) {
        absl::StatusOr<LightBvh> bvh = LightBvh::Build(bounds);
        if (bvh.ok()) {
            bvh_ = *std::move(bvh);
        } else {
            spdlog::warn("light BVH: {}; lights are picked by power",
                         std::string(bvh.status().message()));
            strategy_ = LightStrategy::kPower;
        }
    }
    for (size_t light : sun_lights) sun_pmf_.push_back(pmf_[light]);
    if (environment_) environment_pmf_ = pmf_[environment_light];
}

std::optional<LightSample> LightSampler::Sample(const Vec3& ref, const Vec3& n, float u_pick,
                                                const Vec2& u, float time) const {
    if (lights_.empty()) return std::nullopt;
    int li = 0;
    float pick = 0;
    if (strategy_ == LightStrategy::kBvh && u_pick < finite_pmf_) {
        const std::optional<LightPick> bvh_pick =
            bvh_.Sample(ref, n, std::min(u_pick / finite_pmf_, kOneMinusEpsilon));
        if (!bvh_pick) return std::nullopt;
        li = bvh_pick->light;
        pick = finite_pmf_ * bvh_pick->pmf;
    } else {
        const int index = int(std::upper_bound(cdf_.begin(), cdf_.end(), u_pick) - cdf_.begin());
        li = std::min(index, int(lights_.size()) - 1);
        pick = pmf_[size_t(li)];
    }
    if (!(pick > 0)) return std::nullopt;
    const Light& light = lights_[size_t(li)];

    if (light.kind == Kind::kPoint || light.kind == Kind::kSpot ||
        light.kind == Kind::kDirectional) {
        std::optional<LightSample> ls = SampleDelta(light, ref, time);
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
        ls.at_infinity = true;
        return ls;
    }
    std::optional<LightSample> ls = SampleArea(light, ref, n, u, time);
    if (ls) ls->pdf *= pick;
    return ls;
}

bool LightSampler::IsDeltaLight(size_t i) const {
    const Kind kind = lights_[i].kind;
    return kind == Kind::kPoint || kind == Kind::kSpot || kind == Kind::kDirectional;
}

std::optional<LightSample> LightSampler::SampleDeltaLight(size_t i, const Vec3& ref,
                                                          float time) const {
    if (!IsDeltaLight(i)) return std::nullopt;
    std::optional<LightSample> ls = SampleDelta(lights_[i], ref, time);
    if (ls) ls->pdf = 1;
    return ls;
}

std::optional<LightSample> LightSampler::SampleArea(const Light& light, const Vec3& ref,
                                                    const Vec3& n, const Vec2& u,
                                                    float time) const {
    const Scene& scene = scene_.scene();
    const bool bvh = strategy_ == LightStrategy::kBvh;
    float area = light.area;
    LightSample ls;
    Rgb emission;
    float solid_angle_pdf = 0;  // set when the point was sampled by solid angle
    // A point in a spherical triangle's or rectangle's sample space for u, warped by the
    // receiver's cosine when there is a normal; multiplies solid_angle_pdf by the warp's density.
    const auto warped = [&](const CosineWarp& warp) {
        if (n == Vec3(0, 0, 0)) return u;
        const Vec2 uw = warp.Sample(u);
        solid_angle_pdf *= warp.Pdf(uw);
        return uw;
    };
    if (light.kind == Kind::kTriangle) {
        Vec3 p0, p1, p2;
        scene_.Triangle(light.index, light.primitive, time, &p0, &p1, &p2);
        area = TriangleAreaOf(p0, p1, p2);  // a deforming triangle's, at `time`
        const SphericalTriangle st(ref, p0, p1, p2, kMinSampledSolidAngle);
        if (bvh && st.samplable()) {
            solid_angle_pdf = st.Pdf();
            const Vec2 b = st.Sample(warped(CosineWarp::ForTriangle(ref, n, p0, p1, p2))).b;
            ls.point = scene_.TrianglePoint(light.index, light.primitive, b.x, b.y, time);
        } else {
            // Uniform on the triangle (Osada et al. square-root parameterisation).
            const float su = std::sqrt(u.x);
            ls.point =
                scene_.TrianglePoint(light.index, light.primitive, su * (1 - u.y), su * u.y, time);
        }
        emission = scene.materials[size_t(scene.meshes[size_t(light.index)].material)].emission;
    } else if (light.kind == Kind::kRectangle) {
        const Rectangle& r = rectangles_[size_t(light.primitive)];
        Vec2 st = u;  // uniform on the rectangle unless sampled by solid angle
        if (bvh) {
            const SphericalRectangle sr(ref, r.frame, kMinSampledSolidAngle);
            if (sr.samplable()) {
                solid_angle_pdf = sr.Pdf();
                st = sr.Sample(warped(CosineWarp::ForRectangle(ref, n, r.frame))).uv;
            }
        }
        ls.point = RectanglePoint(light, st);
        emission = scene.materials[size_t(scene.meshes[size_t(light.index)].material)].emission;
    } else {
        if (bvh) {
            const std::optional<SphereConeSample> s =
                SampleSphereCone(ref, scene_.SphereCenter(light.index, time),
                                 float(scene.spheres[size_t(light.index)].radius), u);
            if (!s) return std::nullopt;
            ls.point = scene_.SpherePoint(light.index, s->normal, time);
            solid_angle_pdf = s->pdf;
        } else {
            const float z = 1 - 2 * u.x;
            const float r = std::sqrt(std::max(0.0f, 1 - z * z));
            const float phi = 2 * kPi * u.y;
            ls.point = scene_.SpherePoint(light.index,
                                          Vec3(r * std::cos(phi), r * std::sin(phi), z), time);
        }
        ls.sphere = light.index;
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
    ls.pdf = solid_angle_pdf > 0 ? solid_angle_pdf : dist2 / (cos_light * area);
    return ls;
}

float LightSampler::AreaPdf(const Light& light, const Vec3& ref, const Vec3& n,
                            const SurfaceHit& hit) const {
    if (strategy_ == LightStrategy::kBvh) {
        if (light.kind == Kind::kSphere) {
            return SphereConePdf(ref, scene_.SphereCenter(light.index, hit.time),
                                 float(scene_.scene().spheres[size_t(light.index)].radius), hit.p);
        }
        const bool warp = n != Vec3(0, 0, 0);
        if (light.kind == Kind::kRectangle) {
            const Rectangle& r = rectangles_[size_t(light.primitive)];
            const SphericalRectangle sr(ref, r.frame, kMinSampledSolidAngle);
            if (sr.samplable()) {
                return sr.Pdf() *
                       (warp ? CosineWarp::ForRectangle(ref, n, r.frame).Pdf(sr.Invert(hit.p))
                             : 1.0f);
            }
        } else {
            Vec3 p0, p1, p2;
            scene_.Triangle(light.index, light.primitive, hit.time, &p0, &p1, &p2);
            const SphericalTriangle st(ref, p0, p1, p2, kMinSampledSolidAngle);
            if (st.samplable()) {
                if (!warp) return st.Pdf();
                return st.Pdf() * CosineWarp::ForTriangle(ref, n, p0, p1, p2)
                                      .Pdf(st.Invert(Normalize(hit.p - ref)));
            }
        }
    }
    float area = light.area;
    // A still triangle's area is the list's (the same formula at the same points).
    if (light.kind == Kind::kTriangle && scene_.Moves(light.index)) {
        area = scene_.TriangleArea(light.index, light.primitive, hit.time);
    }
    const Vec3 d = hit.p - ref;
    const float dist2 = LengthSquared(d);
    const float cos_light = std::abs(Dot(hit.n, d)) / std::sqrt(dist2);
    if (!(cos_light > 0)) return 0;
    return dist2 / (cos_light * area);
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

std::optional<LightSample> LightSampler::SampleDelta(const Light& light, const Vec3& ref,
                                                     float time) const {
    const Scene& scene = scene_.scene();
    LightSample ls;
    ls.delta = true;
    if (light.kind == Kind::kDirectional) {
        const DirectionalLight& dl = scene.directional_lights[size_t(light.index)];
        ls.directional_light = light.index;
        ls.wi = -Vec3(Normalize(dl.direction));
        ls.point.p = InfinitePoint(ref, ls.wi);
        ls.point.n = -ls.wi;
        ls.at_infinity = true;
        ls.radiance = dl.irradiance;
        return ls;
    }
    const bool spot = light.kind == Kind::kSpot;
    const EmbreeScene::SpotPlace place =
        spot ? scene_.SpotLightAt(light.index, time)
             : EmbreeScene::SpotPlace{scene_.PointLightPosition(light.index, time), Vec3()};
    (spot ? ls.spot_light : ls.point_light) = light.index;
    ls.point.p = place.position;
    ls.point.time = time;
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
    const float one_minus_cos = 0.5f * LengthSquared(ls.wi + place.direction);
    const float t =
        std::clamp((cone.one_minus_cos_outer - one_minus_cos) * cone.inv_width, 0.0f, 1.0f);
    if (t == 0) return std::nullopt;  // outside the outer cone: no shadow ray needed
    ls.radiance = scene.spot_lights[size_t(light.index)].intensity *
                  (SpotBandFalloff(t, cone.smooth) / dist2);
    return ls;
}

SurfacePoint LightSampler::RectanglePoint(const Light& light, const Vec2& st) const {
    const Rectangle& r = rectangles_[size_t(light.primitive)];
    const Vec3 q = r.frame.corner + r.frame.ex * st.x + r.frame.ey * st.y;
    const Rectangle::Half* h = &r.halves[0];
    float b1 = Dot(q - h->origin, h->dual1), b2 = Dot(q - h->origin, h->dual2);
    if (!(b1 >= 0 && b2 >= 0 && b1 + b2 <= 1)) {
        h = &r.halves[1];
        b1 = Dot(q - h->origin, h->dual1);
        b2 = Dot(q - h->origin, h->dual2);
        // Near the diagonal, rounding may put q a little outside both halves.
        b1 = std::max(b1, 0.0f);
        b2 = std::max(b2, 0.0f);
        if (b1 + b2 > 1) {
            const float sum = b1 + b2;
            b1 /= sum;
            b2 /= sum;
        }
    }
    return scene_.TrianglePoint(light.index, h->primitive, b1, b2, 0);  // never moves
}

int LightSampler::LightIndex(const SurfaceHit& hit) const {
    if (hit.sphere >= 0) return sphere_light_[size_t(hit.sphere)];
    return triangle_light_[size_t(hit.mesh)][size_t(hit.primitive)];
}

float LightSampler::Pdf(const Vec3& ref, const Vec3& n, const SurfaceHit& hit) const {
    const int li = LightIndex(hit);
    if (li < 0) return 0;
    const float pick =
        strategy_ == LightStrategy::kBvh ? finite_pmf_ * bvh_.Pmf(ref, n, li) : pmf_[size_t(li)];
    if (!(pick > 0)) return 0;
    return pick * AreaPdf(lights_[size_t(li)], ref, n, hit);
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
