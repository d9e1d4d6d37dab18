#include "lf/kernels/bdpt.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "lf/kernels/bsdf.h"
#include "lf/kernels/next_event.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/phase_function.h"
#include "lf/kernels/shading.h"

namespace lf {

// A vertex of a camera or light subpath (pbrt-v4's Vertex). Densities are per area at the
// vertex (per solid angle for a vertex at infinity): pdf_fwd that of the subpath's own sampling
// of it, pdf_rev that of sampling it from the other side, which the MIS weight needs. A medium
// vertex (a real scattering event inside a medium) has no normal: its densities carry no cosine.
struct BdptVertex {
    enum class Type : uint8_t { kCamera, kLight, kSurface, kMedium };
    Type type = Type::kSurface;
    Vec3 p;
    SurfacePoint point;  // p with its error bound and geometric normal: where rays start or end
    Vec3 ng, ns;         // geometric and shading normal (surfaces and area-light endpoints)
    bool on_surface = false;
    // Light endpoints and the camera subpath's escaped vertex: at infinity (w is then the
    // direction the light travels), a delta light, which emitter (EmissionSampler's index; -1
    // for the lights at infinity, weighed as one).
    bool infinite = false, delta_light = false;
    Vec3 w;
    int light = -1;
    // Area-light endpoints and emitters the camera subpath hit: the primitive, for the
    // LightSampler's density of choosing this point (LightSampler::Pdf).
    int mesh = -1, primitive = 0, sphere = -1;
    // A light subpath's first vertex: NeeRatio(it, the second vertex), which every strategy
    // with s >= 2 needs (computed once per light subpath).
    float nee_ratio = 1;
    // Surfaces: a delta lobe was sampled here (the vertex cannot be connected).
    bool delta = false;
    // beta: the throughput over the hero channel's density (see the header); r: the subpath's
    // density with each channel as the hero, over the hero's own (1 outside scattering media).
    Rgb beta, r{1.0f};
    float pdf_fwd = 0, pdf_rev = 0;
    // Surfaces: the interaction, the BSDF and its frame, the direction back along the subpath
    // (media too), the material, the medium the subpath arrived through (media: the one it
    // scatters in) and the media on either side of the surface, the emission seen from wo
    // (camera subpaths), and the connection numbers drawn at this vertex (media too).
    Shading sh;
    std::optional<Bsdf> bsdf;
    Frame frame;
    Vec3 wo;
    int material = -1, medium = -1;
    MediumInterface media;
    Rgb le;
    float u_pick = 0;
    Vec2 u_conn;

    bool IsScattering() const { return type == Type::kSurface || type == Type::kMedium; }
    bool IsConnectible() const {
        if (type == Type::kSurface) return !bsdf->IsDelta();
        if (type == Type::kLight) return !(infinite && delta_light);
        return true;
    }
};

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// pbrt's remap of zero densities in the MIS recursion (those that no strategy samples, such as
// a camera or light endpoint's reverse density; delta lobes have their own, see Walk).
float Remap0(float f) { return f != 0 ? f : 1; }

// Unit direction from a to b; towards the light for b at infinity, along its light for a.
Vec3 DirectionTo(const BdptVertex& a, const BdptVertex& b) {
    if (b.infinite) return -b.w;
    if (a.infinite) return a.w;
    return Normalize(b.p - a.p);
}

Rgb ClampToMax(Rgb v, double clamp) {
    if (clamp > 0 && v.MaxComponent() > clamp) v *= float(clamp / v.MaxComponent());
    return v;
}

constexpr int kRouletteStartBounce = 2;  // the path tracer's depth 1: its second bounce

// Connections whose transmittance estimate has fallen this low play roulette (as the path
// tracer's shadow rays): most of them end, the survivors carry 4x.
constexpr float kShadowRouletteBelow = 0.05f;
constexpr float kShadowRouletteStop = 0.75f;

Rgb ClampZero(const Rgb& c) {
    return {std::max(0.0f, c.r), std::max(0.0f, c.g), std::max(0.0f, c.b)};
}

// Where a ray from scattering vertex v towards dir starts.
SurfacePoint Leaving(const BdptVertex& v, const Vec3& dir) {
    return v.type == BdptVertex::Type::kSurface ? v.sh.Leaving(dir) : v.point;
}

// The emitter surface a light or emitter vertex lies on, for LightSampler::Pdf and InterfaceAt.
SurfaceHit HitOf(const BdptVertex& v) {
    return {.p = v.p,
            .n = v.ng,
            .mesh = v.mesh,
            .sphere = v.sphere,
            .primitive = v.primitive,
            .time = v.point.time};
}

}  // namespace

struct BdptRenderer::Scratch {
    Path camera, light;
};

// A camera sample's channel choice and the random numbers of its walks through media beyond
// the sampler's fixed dimensions (delta and ratio tracking take as many as they meet
// collisions).
struct BdptRenderer::Spectral {
    int hero = 0;
    MediumRng rng{0};
};

BdptRenderer::BdptRenderer(const EmbreeScene& scene, const Camera& camera,
                           const SplatRenderSettings& settings)
    : scene_(scene),
      camera_(camera),
      settings_(settings),
      lights_(scene, settings.light_strategy),
      emission_(scene),
      media_(scene.media()) {
    const float r = emission_.scene_radius();
    infinite_pdf_pos_ = 1 / (std::numbers::pi_v<float> * r * r);
    has_infinite_ = scene.scene().environment.has_value();
    for (const DirectionalLight& dl : scene.scene().directional_lights) {
        if (dl.angular_diameter > 0) has_infinite_ = true;
    }
    const Scene& s = scene.scene();
    volumetric_ = s.camera_medium >= 0;
    for (const Material& m : s.materials) volumetric_ |= m.type == Material::Type::kInterface;
    for (int m = 0; m < int(s.media.size()); ++m) volumetric_ |= !media_.IsHomogeneousAbsorber(m);
}

BdptRenderer::~BdptRenderer() = default;

float BdptRenderer::ConvertDensity(const BdptVertex& from, float pdf,
                                   const BdptVertex& next) const {
    if (next.infinite) return pdf;
    if (from.infinite) {
        // A ray from the disk of a light at infinity: the disk's density, projected.
        return infinite_pdf_pos_ * (next.on_surface ? std::abs(Dot(next.ng, from.w)) : 1.0f);
    }
    const Vec3 d = next.p - from.p;
    const float dist2 = LengthSquared(d);
    if (!(dist2 > 0)) return 0;
    if (next.on_surface) pdf *= std::abs(Dot(next.ng, d)) / std::sqrt(dist2);
    return pdf / dist2;
}

float BdptRenderer::PdfLight(const BdptVertex& v, const BdptVertex& next) const {
    if (v.infinite) {
        return infinite_pdf_pos_ * (next.on_surface ? std::abs(Dot(next.ng, v.w)) : 1.0f);
    }
    if (v.light < 0) return 0;
    const Vec3 d = next.p - v.p;
    const float dist2 = LengthSquared(d);
    if (!(dist2 > 0)) return 0;
    const Vec3 w = d / std::sqrt(dist2);
    float pdf = emission_.PdfLe(v.light, v.p, v.ng, w, v.point.time).dir / dist2;
    if (next.on_surface) pdf *= std::abs(Dot(next.ng, w));
    return pdf;
}

float BdptRenderer::PdfLightOrigin(const BdptVertex& v, const BdptVertex& next) const {
    if (v.infinite) {
        // A delta directional light: its pick (the direction is certain); the others as one.
        if (v.light >= 0) return emission_.Pmf(v.light);
        return emission_.EscapedPdfLe(-v.w).dir;
    }
    if (v.light < 0) return 0;
    const Vec3 w = DirectionTo(v, next);
    return emission_.Pmf(v.light) * emission_.PdfLe(v.light, v.p, v.ng, w, v.point.time).pos;
}

float BdptRenderer::NeeRatio(const BdptVertex& v, const BdptVertex& ref) const {
    // Delta lights: both strategies pick them (the emission pick stands for both).
    if (v.delta_light) return 1;
    const float emit = PdfLightOrigin(v, ref);
    if (!(emit > 0)) return 1;
    if (v.infinite) return lights_.EscapedPdf(DirectionTo(ref, v)) / emit;
    const SurfaceHit hit = HitOf(v);
    if (hit.mesh < 0 && hit.sphere < 0) return 1;
    const Vec3 d = v.p - ref.p;
    const float dist2 = LengthSquared(d);
    if (!(dist2 > 0)) return 1;
    const float cos_light = std::abs(Dot(v.ng, d)) / std::sqrt(dist2);
    return lights_.Pdf(ref.p, ref.ns, hit) * cos_light / (dist2 * emit);
}

float BdptRenderer::PdfTo(const BdptVertex& v, const BdptVertex* prev,
                          const BdptVertex& next) const {
    if (v.type == BdptVertex::Type::kLight) return PdfLight(v, next);
    const Vec3 wn = DirectionTo(v, next);
    float pdf = 0;
    if (v.type == BdptVertex::Type::kCamera) {
        pdf = camera_.PdfWe(Ray{v.p, wn, kInfinity, v.point.time}).dir;
    } else if (v.type == BdptVertex::Type::kMedium) {
        if (prev == nullptr) return 0;
        pdf = HenyeyGreenstein(-Dot(DirectionTo(v, *prev), wn), media_.g(v.medium));
    } else {
        if (prev == nullptr) return 0;
        const Vec3 wp = DirectionTo(v, *prev);
        pdf = v.bsdf->Pdf(v.frame.ToLocal(wp), v.frame.ToLocal(wn));
    }
    return ConvertDensity(v, pdf, next);
}

Rgb BdptRenderer::FCos(const BdptVertex& v, const Vec3& dir, bool importance) const {
    // The phase function is symmetric and has no cosine: radiance and importance alike.
    if (v.type == BdptVertex::Type::kMedium) {
        return Rgb(HenyeyGreenstein(-Dot(v.wo, dir), media_.g(v.medium)));
    }
    const Vec3 wo = v.frame.ToLocal(v.wo), wi = v.frame.ToLocal(dir);
    const bool reflect = wi.z * wo.z > 0;
    if (!v.sh.SidesAgree(v.wo, dir, reflect)) return Rgb(0);
    const Rgb f = v.bsdf->Eval(wo, wi);
    if (!importance) return f * std::abs(wi.z);
    // The adjoint BSDF: radiance crossing a refracting interface is scaled by 1/eta^2
    // (eta = IOR on wi's side over wo's), importance is not.
    float scale = 1;
    const Material& material = scene_.scene().materials[size_t(v.material)];
    if (!reflect && material.HasInterior()) {
        const float eta = wo.z > 0 ? material.ior : 1 / material.ior;
        scale = eta * eta;
    }
    const float wo_ng = std::abs(Dot(v.wo, v.ng));
    if (!(wo_ng > 0)) return Rgb(0);
    return f * (scale * std::abs(wo.z) * std::abs(Dot(dir, v.ng)) / wo_ng);
}

int BdptRenderer::MediumToward(const BdptVertex& v, const Vec3& dir) const {
    if (v.type == BdptVertex::Type::kMedium) return v.medium;
    if (v.type != BdptVertex::Type::kSurface) return -1;
    const bool transmitted = v.frame.ToLocal(dir).z * v.frame.ToLocal(v.wo).z < 0;
    return transmitted ? MediumAfter(v.media, v.medium, v.ng, dir) : v.medium;
}

Rgb BdptRenderer::Transmission(const BdptVertex& from, const BdptVertex& to, Spectral& spectral,
                               RenderStats& stats) const {
    const Vec3 dir = DirectionTo(from, to);
    int medium = MediumToward(from, dir);
    Ray ray = SpawnRayTo(Leaving(from, dir), to.point);
    if (!volumetric_) {
        ++stats.rays;
        if (scene_.Occluded(ray)) return Rgb(0);
        return Attenuation(scene_, medium, Length(to.p - from.p));
    }
    // Interface surfaces are crossed, any other surface blocks; every medium on the way
    // attenuates.
    Rgb tr(1.0f);
    for (int crossed = 0; crossed <= kMaxInterfaceCrossings; ++crossed) {
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
        if (hit &&
            scene_.scene().materials[size_t(hit->material)].type != Material::Type::kInterface) {
            return Rgb(0);
        }
        if (medium >= 0) {
            // Towards a light at infinity the medium goes on past the scene, as for a camera
            // path that escapes (VolPathTracer does the same).
            const float t_end = hit ? hit->t : to.infinite ? kInfinity : ray.t_max;
            tr *= SegmentTransmittance(medium, ray, t_end, spectral);
            if (tr.IsBlack()) return tr;
        }
        if (!hit) return tr;
        medium = MediumAfter(scene_.scene(), medium, *hit, ray.d);
        ray = SpawnRayTo(HitPoint(*hit), to.point);
    }
    return Rgb(0);  // degenerate interfaces: blocked
}

Rgb BdptRenderer::SegmentTransmittance(int medium, const Ray& ray, float t_end,
                                       Spectral& spectral) const {
    // Beer's law exactly where nothing but absorption happens.
    if (media_.IsHomogeneousAbsorber(medium)) {
        return media_.HomogeneousTransmittance(medium, t_end * Length(ray.d));
    }
    // Ratio tracking against the hero's majorant: unbiased in every channel for any hero.
    const int hero = spectral.hero;
    Rgb tr(1.0f);
    const Rgb t_maj = media_.SampleTMaj(
        medium, ray, t_end, hero, spectral.rng,
        [&](const Vec3&, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb& tm) {
            const Rgb sigma_n = ClampZero(sigma_maj - mp.sigma_a - mp.sigma_s);
            tr *= tm * sigma_n / (tm[hero] * sigma_maj[hero]);
            if (tr.MaxComponent() < kShadowRouletteBelow) {
                if (spectral.rng.Uniform() < kShadowRouletteStop) {
                    tr = Rgb(0);
                } else {
                    tr /= 1 - kShadowRouletteStop;
                }
            }
            return !tr.IsBlack();
        });
    if (tr.IsBlack() || !(t_maj[hero] > 0)) return Rgb(0);
    return tr * t_maj / t_maj[hero];
}

int BdptRenderer::MediumAtLight(const BdptVertex& eye, const BdptVertex& light,
                                RenderStats& stats) const {
    const Scene& scene = scene_.scene();
    if (!volumetric_) return -1;
    // The media the segment from the camera to the light crosses, as a path would.
    int medium = scene.camera_medium;
    Ray ray = SpawnRayTo(eye.point, light.point);
    for (int i = 0; i < kMaxInterfaceCrossings; ++i) {
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
        if (!hit) break;
        medium = MediumAfter(scene, medium, *hit, ray.d);
        ray = SpawnRayTo(HitPoint(*hit), light.point);
    }
    // An area light's own surface separates the side the segment arrives on from the side
    // it emits into.
    if (light.on_surface)
        medium = MediumAfter(InterfaceAt(scene, HitOf(light)), medium, light.ng, light.w);
    return medium;
}

void BdptRenderer::Walk(Ray ray, Rgb beta, float pdf_fwd, int max_vertices, bool importance,
                        int medium, Spectral& spectral, Sampler& sampler, Path& path,
                        RenderStats& stats) const {
    if (max_vertices <= 0) return;
    const std::vector<Material>& materials = scene_.scene().materials;
    const float beta0 = beta.MaxComponent();
    const int hero = spectral.hero;
    Rgb r(1.0f);
    float eta_scale = 1;
    int crossings = 0;  // interface surfaces this path has passed (kMaxInterfaceCrossings)
    for (int bounces = 0;;) {
        // The vertex's numbers, drawn before the ray is traced and in the same order whatever
        // happens (see the header): lobe and light pick, connection, direction, roulette.
        const Vec2 u_choice = sampler.Get2D(), u_conn = sampler.Get2D(), u_bsdf = sampler.Get2D();
        const float u_roulette = sampler.Get1D();
        ray.d = Normalize(ray.d);
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);

        // Delta tracking through a scattering medium (as VolPathTracer::Li): a real collision
        // is absorbed (the subpath ends) or scatters (a medium vertex), a null one reweighs.
        std::optional<Vec3> scattered_at;
        if (medium >= 0 && !media_.IsHomogeneousAbsorber(medium)) {
            bool terminated = false;
            const Rgb t_maj = media_.SampleTMaj(
                medium, ray, hit ? hit->t : kInfinity, hero, spectral.rng,
                [&](const Vec3& p, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb& tm) {
                    const float u = spectral.rng.Uniform(), maj = sigma_maj[hero];
                    const float p_absorb = mp.sigma_a[hero] / maj;
                    if (u < p_absorb) {
                        terminated = true;
                        return false;
                    }
                    const bool real = u < p_absorb + mp.sigma_s[hero] / maj;
                    const Rgb sigma =
                        real ? mp.sigma_s : ClampZero(sigma_maj - mp.sigma_a - mp.sigma_s);
                    const float pdf = tm[hero] * sigma[hero];
                    if (!(pdf > 0)) {
                        terminated = true;
                        return false;
                    }
                    beta *= tm * sigma / pdf;
                    r *= tm * sigma / pdf;
                    if (beta.IsBlack() || r.IsBlack()) {
                        terminated = true;
                        return false;
                    }
                    if (real) scattered_at = p;
                    return !real;
                });
            if (terminated) return;
            if (!scattered_at) {
                const float th = t_maj[hero];
                if (!(th > 0)) return;
                beta *= t_maj / th;
                r *= t_maj / th;
                if (beta.IsBlack()) return;
            }
        }
        if (!scattered_at && !hit) {
            // An escape through a Beer's-law absorber crosses an infinite stretch of it.
            if (medium >= 0 && media_.IsHomogeneousAbsorber(medium)) {
                beta *= Attenuation(scene_, medium, kInfinity);
                if (beta.IsBlack()) return;
            }
            if (!importance && has_infinite_) {
                BdptVertex v;
                v.type = BdptVertex::Type::kLight;
                v.infinite = true;
                v.w = -ray.d;
                v.p = ray.o + ray.d;
                v.beta = beta;
                v.r = r;
                v.pdf_fwd = pdf_fwd;
                v.le = lights_.EscapedRadiance(ray.d);
                path.push_back(v);
            }
            return;
        }
        if (!scattered_at && medium >= 0 && media_.IsHomogeneousAbsorber(medium)) {
            beta *= Attenuation(scene_, medium, hit->t * Length(ray.d));
            if (beta.IsBlack()) return;
        }
        if (!scattered_at && materials[size_t(hit->material)].type == Material::Type::kInterface) {
            // Not a vertex: the ray goes on into the medium beyond (its density is unchanged).
            if (++crossings > kMaxInterfaceCrossings) return;
            medium = MediumAfter(scene_.scene(), medium, *hit, ray.d);
            ray = SpawnRay(HitPoint(*hit), ray.d);
            continue;
        }
        BdptVertex v;
        if (scattered_at) {
            v.type = BdptVertex::Type::kMedium;
            v.p = *scattered_at;
            v.point.p = v.p;
            v.point.time = ray.time;
        } else {
            v.type = BdptVertex::Type::kSurface;
            v.sh = Shade(scene_, *hit, -ray.d);
            v.point = v.sh.point;
            v.p = hit->p;
            v.ng = hit->n;
            v.ns = v.sh.ns;
            v.on_surface = true;
            v.material = hit->material;
            v.media = InterfaceAt(scene_.scene(), *hit);
            v.frame = Frame::FromNormal(v.sh.ns);
            v.bsdf.emplace(materials[size_t(hit->material)], v.sh.params);
        }
        v.medium = medium;
        v.wo = -ray.d;
        v.beta = beta;
        v.r = r;
        v.pdf_fwd = ConvertDensity(path.back(), pdf_fwd, v);
        v.u_pick = u_choice.x;
        v.u_conn = u_conn;
        if (!scattered_at && !importance && !v.sh.emission.IsBlack() &&
            (Dot(ray.d, hit->n) < 0 || EmitsFromBack(materials[size_t(hit->material)]))) {
            v.light = emission_.LightOf(*hit);
            if (v.light >= 0) v.le = v.sh.emission;
            v.mesh = hit->mesh;
            v.primitive = hit->primitive;
            v.sphere = hit->sphere;
        }
        path.push_back(std::move(v));
        if (++bounces >= max_vertices) {
            // Unlimited depth stops at kBdptUnlimitedDepth (see the header): a cut path.
            if (settings_.max_depth < 0) ++stats.truncated_paths;
            return;
        }
        BdptVertex& cur = path.back();
        BdptVertex& prev = path[path.size() - 2];
        Vec3 wi;
        float pdf_rev = 0;
        if (scattered_at) {
            // The phase function is sampled exactly and is symmetric: beta keeps its value,
            // and the reverse density is the forward one.
            const PhaseSample ps = SampleHenyeyGreenstein(ray.d, media_.g(medium), u_bsdf);
            if (!(ps.pdf > 0)) return;
            wi = ps.wi;
            pdf_fwd = pdf_rev = ps.pdf;
        } else {
            const Vec3 wo = cur.frame.ToLocal(cur.wo);
            const std::optional<BsdfSample> bs = cur.bsdf->Sample(wo, u_choice.y, u_bsdf);
            if (!bs || !(bs->pdf > 0)) return;
            wi = cur.frame.FromLocal(bs->wi);
            if (!cur.sh.SidesAgree(cur.wo, wi, bs->wi.z * wo.z > 0)) return;
            const bool transmitted = bs->wi.z * wo.z < 0;
            if (importance) {
                // Adjoint: no 1/eta^2 across refraction; shading-normal correction (Veach 5.3).
                const float wo_ng = std::abs(Dot(cur.wo, cur.ng));
                if (!(wo_ng > 0)) return;
                beta *= bs->f * (bs->eta * bs->eta * std::abs(wo.z) * std::abs(Dot(wi, cur.ng)) /
                                 (wo_ng * bs->pdf));
            } else {
                beta *= bs->f * (std::abs(bs->wi.z) / bs->pdf);
                eta_scale *= bs->eta * bs->eta;
            }
            if (beta.IsBlack()) return;
            pdf_fwd = bs->pdf;
            pdf_rev = cur.bsdf->Pdf(bs->wi, wo);
            if (bs->delta) {
                // A delta lobe has no density. For the MIS ratios it counts as density 1 in the
                // measure that reflection and refraction preserve, n^2 times projected solid
                // angle, as in Veach's thesis (10.3.5), where the geometry terms stay: n_wi^2
                // |cos wi| per solid angle towards wi and n_wo^2 |cos wo| back towards wo (both
                // divided by n_wo^2 here; a factor common to the two directions cancels in every
                // ratio). Then two strategies that traverse a specular chain from opposite ends
                // compare as they truly do: a camera path E D S S L through glass to a small
                // lamp against the light path L S S D joined to the camera by p_emission(L)
                // p(L -> S) / (p_camera(D) p(D -> S)) in projected solid angle. pbrt-v4 remaps
                // the area density to 1 instead, which drops the geometry term of every segment
                // that leaves a delta vertex and so misjudges that ratio by G(D, S) / G(S, L): in
                // a caustic where the floor D almost touches the glass it is thousands, and the
                // camera path took the weight that belongs to light tracing (BdptTest's caustic
                // test measures it).
                cur.delta = true;
                pdf_fwd = bs->eta * bs->eta * std::abs(Dot(wi, cur.ng));
                pdf_rev = std::abs(Dot(cur.wo, cur.ng));
            }
            if (transmitted) medium = MediumAfter(cur.media, medium, cur.ng, wi);
        }
        prev.pdf_rev = ConvertDensity(cur, pdf_rev, prev);
        ray = SpawnRay(Leaving(cur, wi), wi);
        if (bounces >= kRouletteStartBounce) {
            // On the throughput as the estimate weighs it (over the channels' mean density).
            const float carried = beta.MaxComponent() / r.Average();
            const float relative = importance ? carried / beta0 : carried * eta_scale;
            const float q = std::max(0.0f, 1 - relative);
            if (u_roulette < q) return;
            beta /= 1 - q;
        }
    }
}

void BdptRenderer::LightSubpath(float u_pick, const Vec2& u_pos, const Vec2& u_dir, float time,
                                const BdptVertex& eye, Spectral& spectral, Sampler& sampler,
                                Path& path, RenderStats& stats) const {
    const std::optional<EmissionSample> es = emission_.Sample(u_pick, u_pos, u_dir, time);
    if (!es) return;
    BdptVertex v;
    v.type = BdptVertex::Type::kLight;
    v.light = es->light;
    v.infinite = emission_.AtInfinity(es->light);
    v.delta_light = es->delta_pos || es->delta_dir;
    v.on_surface = !v.infinite && !es->delta_pos;
    v.point = es->point;
    v.mesh = es->point.mesh;
    v.primitive = es->point.primitive;
    v.sphere = es->sphere;
    v.p = es->point.p;
    v.ng = v.ns = es->point.n;
    v.w = es->w;
    v.le = es->le;
    if (v.infinite) {
        v.pdf_fwd = es->delta_dir ? emission_.Pmf(es->light) : emission_.EscapedPdfLe(-es->w).dir;
        // Sun disks and the sky are weighed as one (lights at infinity have no own index).
        if (!es->delta_dir) v.light = -1;
    } else {
        v.pdf_fwd = es->pick * es->pdf_pos;
    }
    const float cos = v.on_surface ? std::abs(Dot(es->point.n, es->w)) : 1.0f;
    v.beta = es->le * (cos / (es->pick * es->pdf_pos * es->pdf_dir));
    path.push_back(v);
    const int max_vertices = settings_.max_depth < 0 ? kBdptUnlimitedDepth : settings_.max_depth;
    const int medium = MediumAtLight(eye, v, stats);
    if (v.infinite && medium >= 0) {
        // Light from infinity has crossed the medium all the way from there to the disk it
        // starts on: its transmittance (0 for a medium that fills all space), estimated by
        // ratio tracking outwards, as escaping camera paths and shadow rays see it.
        const Ray outward{es->point.p, -es->w, kInfinity, es->point.time};
        path[0].beta *= SegmentTransmittance(medium, outward, kInfinity, spectral);
        if (path[0].beta.IsBlack()) return;
    }
    Walk(es->ray(), path[0].beta, es->pdf_dir, max_vertices, true, medium, spectral, sampler, path,
         stats);
}

float BdptRenderer::MisWeight(Path& light, Path& camera, int s, int t) const {
    if (s + t == 2) return 1;
    BdptVertex* qs = s > 0 ? &light[size_t(s - 1)] : nullptr;
    BdptVertex* pt = t > 0 ? &camera[size_t(t - 1)] : nullptr;
    BdptVertex* qs_minus = s > 1 ? &light[size_t(s - 2)] : nullptr;
    BdptVertex* pt_minus = t > 1 ? &camera[size_t(t - 2)] : nullptr;

    // The densities of the connection's ends as the other side would sample them; set for this
    // strategy and restored afterwards (pbrt's ScopedAssignment).
    const float pt_rev = s > 0 ? PdfTo(*qs, qs_minus, *pt) : PdfLightOrigin(*pt, *pt_minus);
    const float pt_minus_rev =
        pt_minus ? (s > 0 ? PdfTo(*pt, qs, *pt_minus) : PdfLight(*pt, *pt_minus)) : 0;
    const float qs_rev = qs ? PdfTo(*pt, pt_minus, *qs) : 0;
    const float qs_minus_rev = qs_minus ? PdfTo(*qs, pt, *qs_minus) : 0;

    struct Saved {
        float* at;
        float value;
    };
    Saved saved[4];
    int n_saved = 0;
    const auto assign = [&](float& at, float value) {
        saved[n_saved++] = {&at, at};
        at = value;
    };
    bool pt_delta = false, qs_delta = false;
    assign(pt->pdf_rev, pt_rev);
    if (pt_minus) assign(pt_minus->pdf_rev, pt_minus_rev);
    if (qs) assign(qs->pdf_rev, qs_rev);
    if (qs_minus) assign(qs_minus->pdf_rev, qs_minus_rev);
    std::swap(pt_delta, pt->delta);
    if (qs) std::swap(qs_delta, qs->delta);

    // Power heuristic: the sum over the other strategies of (p_i / p_{s,t})^2. The chain
    // gives every strategy with a light vertex x0 the emission density of x0; strategy 1 (next
    // event) samples x0 with the LightSampler instead, so its own term is scaled by
    // nee = p_LightSampler(x0 | x1) / p_emission(x0), and when it is the strategy weighed, all the
    // others by 1 / nee.
    double sum = 0, ri = 1;
    for (int i = t - 1; i > 0; --i) {
        ri *= Remap0(camera[size_t(i)].pdf_rev) / Remap0(camera[size_t(i)].pdf_fwd);
        if (!camera[size_t(i)].delta && !camera[size_t(i - 1)].delta) {
            // s = 0: the term of i = t - 1 is next-event estimation's from camera[t - 2].
            const double nee = s == 0 && i == t - 1 ? NeeRatio(*pt, *pt_minus) : 1.0;
            sum += ri * ri * nee * nee;
        }
    }
    ri = 1;
    for (int i = s - 1; i >= 0; --i) {
        ri *= Remap0(light[size_t(i)].pdf_rev) / Remap0(light[size_t(i)].pdf_fwd);
        const bool delta_before = i > 0 ? light[size_t(i - 1)].delta : light[0].delta_light;
        if (!light[size_t(i)].delta && !delta_before) {
            const double nee = s >= 2 && i == 1 ? light[0].nee_ratio : 1.0;
            sum += ri * ri * nee * nee;
        }
    }
    if (s == 1) {
        const double nee = NeeRatio(light[0], *pt);
        if (nee > 0) sum /= nee * nee;
    }

    std::swap(pt_delta, pt->delta);
    if (qs) std::swap(qs_delta, qs->delta);
    while (n_saved > 0) {
        --n_saved;
        *saved[n_saved].at = saved[n_saved].value;
    }
    return float(1 / (1 + sum));
}

Rgb BdptRenderer::Connect(Path& light, Path& camera, int s, int t, Vec2* raster, Spectral& spectral,
                          RenderStats& stats) const {
    using Type = BdptVertex::Type;
    BdptVertex& pt = camera[size_t(t - 1)];
    // An escaped camera vertex is only ever an emitter (s = 0).
    if (t > 1 && s != 0 && pt.type == Type::kLight) return Rgb(0);
    Rgb L(0);
    if (s == 0) {
        if (pt.le.IsBlack()) return Rgb(0);
        L = pt.beta * pt.le / pt.r.Average();
        if (L.IsBlack()) return L;
        return L * MisWeight(light, camera, s, t);
    }
    if (t == 1) {
        BdptVertex& qs = light[size_t(s - 1)];
        if (!qs.IsScattering() || !qs.IsConnectible()) return Rgb(0);
        const std::optional<Camera::ImportanceSample> cs =
            camera_.SampleWi(qs.p, camera_.HasLens() ? qs.u_conn : Vec2{}, qs.point.time);
        if (!cs || !(cs->pdf > 0)) return Rgb(0);
        BdptVertex sampled;
        sampled.type = Type::kCamera;
        sampled.p = cs->lens_point;
        sampled.point.p = cs->lens_point;
        sampled.point.time = qs.point.time;
        sampled.beta = Rgb(cs->we / cs->pdf);
        L = qs.beta * FCos(qs, cs->wi, true) * sampled.beta / qs.r.Average();
        if (L.IsBlack()) return L;
        L *= Transmission(qs, sampled, spectral, stats);
        if (L.IsBlack()) return L;
        *raster = cs->raster;
        std::swap(camera[0], sampled);
        const float w = MisWeight(light, camera, s, t);
        std::swap(camera[0], sampled);
        return L * w;
    }
    if (s == 1) {
        if (!pt.IsScattering() || !pt.IsConnectible()) return Rgb(0);
        const std::optional<LightSample> ls =
            lights_.Sample(pt.p, pt.ns, pt.u_pick, pt.u_conn, pt.point.time);
        if (!ls || !(ls->pdf > 0)) return Rgb(0);
        BdptVertex sampled;
        sampled.type = Type::kLight;
        sampled.light = emission_.LightOf(*ls);
        sampled.infinite = sampled.light < 0 || ls->directional_light >= 0;
        sampled.delta_light = ls->delta;
        sampled.on_surface = !ls->delta && !sampled.infinite;
        sampled.point = ls->point;
        sampled.mesh = ls->point.mesh;
        sampled.primitive = ls->point.primitive;
        sampled.sphere = ls->sphere;
        sampled.p = ls->point.p;
        sampled.ng = sampled.ns = ls->point.n;
        sampled.w = -ls->wi;
        const Rgb radiance =
            sampled.on_surface ? EmissionAt(scene_, ls->point, ls->radiance) : ls->radiance;
        sampled.beta = radiance / ls->pdf;
        L = pt.beta * FCos(pt, ls->wi, false) * sampled.beta / pt.r.Average();
        if (L.IsBlack()) return L;
        L *= Transmission(pt, sampled, spectral, stats);
        if (L.IsBlack()) return L;
        sampled.pdf_fwd = PdfLightOrigin(sampled, pt);
        std::swap(light[0], sampled);
        const float w = MisWeight(light, camera, s, t);
        std::swap(light[0], sampled);
        return L * w;
    }
    BdptVertex& qs = light[size_t(s - 1)];
    if (!qs.IsScattering() || !pt.IsScattering() || !qs.IsConnectible() || !pt.IsConnectible()) {
        return Rgb(0);
    }
    const Vec3 d = qs.p - pt.p;
    const float dist2 = LengthSquared(d);
    if (!(dist2 > 0)) return Rgb(0);
    const Vec3 w = d / std::sqrt(dist2);  // from the camera vertex to the light vertex
    L = qs.beta * FCos(qs, -w, true) * FCos(pt, w, false) * pt.beta /
        (dist2 * (qs.r * pt.r).Average());
    if (L.IsBlack()) return L;
    L *= Transmission(pt, qs, spectral, stats);
    if (L.IsBlack()) return L;
    return L * MisWeight(light, camera, s, t);
}

Rgb BdptRenderer::Sample(int x, int y, uint64_t sample_index, SplatList& splats,
                         RenderStats& stats) const {
    thread_local Scratch scratch;
    Path& camera = scratch.camera;
    Path& light = scratch.light;
    camera.clear();
    light.clear();

    Sampler sampler(settings_.seed, x, y, sample_index, settings_.sampler);
    const Vec2 film = camera_.SampleFilm(sampler.Get2D());
    const Vec2 lens = camera_.HasLens() ? sampler.Get2D() : Vec2{};
    const float u_pick = sampler.Get1D();
    const Vec2 u_pos = sampler.Get2D(), u_dir = sampler.Get2D();
    // Both subpaths at one time in the shutter: every connection joins the same instant.
    const float time = sampler.GetTime();

    const Ray ray = camera_.GenerateRay(x, y, film.x, film.y, lens, time);
    BdptVertex cv;
    cv.type = BdptVertex::Type::kCamera;
    cv.p = ray.o;
    cv.point.p = ray.o;
    cv.point.time = time;
    cv.beta = Rgb(1);
    camera.push_back(cv);
    const Camera::ImportancePdf pdf = camera_.PdfWe(Ray{ray.o, Normalize(ray.d), kInfinity, time});
    const int max_depth = settings_.max_depth < 0 ? kBdptUnlimitedDepth : settings_.max_depth;
    // The hero channel and the media's random numbers come from their own stream (a pure
    // function of the sample), so the sampler's dimensions stay those of the header.
    Spectral spectral;
    spectral.rng = MediumRng(MixBits(MixBits(settings_.seed ^ 0x5bd1e995a3c7f2b1ULL) ^
                                     (uint64_t(uint32_t(x)) << 32 | uint32_t(y))) ^
                             MixBits(sample_index));
    spectral.hero = std::min(2, int(spectral.rng.Uniform() * 3));
    Walk(ray, Rgb(1), pdf.dir, max_depth + 1, false, scene_.scene().camera_medium, spectral,
         sampler, camera, stats);
    LightSubpath(u_pick, u_pos, u_dir, time, camera[0], spectral, sampler, light, stats);

    const int nc = int(camera.size()), nl = int(light.size());
    if (nl >= 2) light[0].nee_ratio = NeeRatio(light[0], light[1]);
    // s = 1 uses its own light sample, so it needs a slot even without a light subpath.
    if (light.empty()) light.emplace_back();
    Rgb L(0);
    for (int t = 1; t <= nc; ++t) {
        for (int s = 0; s <= std::max(nl, 1); ++s) {
            const int depth = s + t - 2;
            if ((s == 1 && t == 1) || depth < 0 || depth > max_depth) continue;
            if (s > 1 && s > nl) continue;
            if (t == 1) {
                Vec2 raster;
                Rgb c = Connect(light, camera, s, t, &raster, spectral, stats);
                if (c.IsBlack()) continue;
                if (!c.IsFinite()) {
                    ++stats.invalid_samples;
                    continue;
                }
                const int px = std::clamp(int(raster.x), 0, camera_.width() - 1);
                const int py = std::clamp(int(raster.y), 0, camera_.height() - 1);
                splats.Add(px, py, int(sample_index & 1), ClampToMax(c, settings_.clamp));
            } else {
                L += Connect(light, camera, s, t, nullptr, spectral, stats);
            }
        }
    }
    return L;
}

void BdptRenderer::Render(const SplatWork& work, TileSums& camera, SplatList& splats,
                          const std::atomic<bool>* cancel) const {
    const PixelRect& rect = work.rect;
    if (rect.Area() <= 0 || work.sample_end <= work.sample_begin) return;
    struct Row {
        TileSums sums;
        SplatList splats;
    };
    std::vector<Row> rows;
    rows.reserve(size_t(rect.height));
    for (int y = 0; y < rect.height; ++y) {
        rows.push_back({TileSums(PixelRect{rect.x0, rect.y0 + y, rect.width, 1}),
                        SplatList(splats.width(), splats.height())});
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, rect.height, 1),
                      [&](const tbb::blocked_range<int>& range) {
                          for (int r = range.begin(); r < range.end(); ++r) {
                              if (cancel && cancel->load(std::memory_order_relaxed)) return;
                              Row& row = rows[size_t(r)];
                              const int y = rect.y0 + r;
                              for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
                                  PixelSums& pixel = row.sums.at(x, y);
                                  for (uint64_t s = work.sample_begin; s < work.sample_end; ++s) {
                                      Rgb L = Sample(x, y, s, row.splats, row.sums.stats);
                                      if (!L.IsFinite()) {
                                          ++row.sums.stats.invalid_samples;
                                          L = Rgb(0);
                                      }
                                      pixel.Add(s, ClampToMax(L, settings_.clamp));
                                  }
                              }
                              row.sums.stats.samples +=
                                  uint64_t(rect.width) * (work.sample_end - work.sample_begin);
                          }
                      });
    for (int r = 0; r < rect.height; ++r) {
        const Row& row = rows[size_t(r)];
        const int y = rect.y0 + r;
        for (int x = rect.x0; x < rect.x0 + rect.width; ++x) camera.at(x, y) += row.sums.at(x, y);
        camera.stats += row.sums.stats;
        splats += row.splats;
    }
}

}  // namespace lf
