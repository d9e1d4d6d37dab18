#include "lf/kernels/vol_path_tracer.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lf/kernels/aov_tracer.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/next_event.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/phase_function.h"
#include "lf/kernels/shading.h"

namespace lf {

namespace {

constexpr int kRouletteStartDepth = 1;

// Shadow rays whose transmittance estimate has fallen this low play roulette (pbrt-v4's
// choice): most of them end, the survivors carry 4x.
constexpr float kShadowRouletteBelow = 0.05f;
constexpr float kShadowRouletteStop = 0.75f;

// The hero channel's component.
float Channel(const Rgb& c, int hero) { return c[hero]; }

Rgb ClampZero(const Rgb& c) {
    return {std::max(0.0f, c.r), std::max(0.0f, c.g), std::max(0.0f, c.b)};
}

// A 64-bit seed from one 2D draw (48 bits of it) and the bounce: the walk's own stream.
uint64_t WalkSeed(const Vec2& u, int depth) {
    const uint64_t bits = (uint64_t(u.x * 0x1p24f) << 24) | uint64_t(u.y * 0x1p24f);
    return MixBits(bits ^ (uint64_t(uint32_t(depth)) << 48));
}

SurfacePoint PointInMedium(const Vec3& p, float time) {
    SurfacePoint sp;
    sp.p = p;
    sp.time = time;
    return sp;
}

}  // namespace

// What a path carries: its throughput over the hero channel's density, and the per-channel
// densities of the unidirectional (r_u) and light-sampling (r_l) strategies over the hero's.
struct VolPathTracer::PathState {
    Rgb beta{1.0f}, r_u{1.0f}, r_l{1.0f};
    int hero = 0;
};

// PathTracer's roulette on the MIS-weighted throughput, after a surface bounce or a scattering
// in a medium (thick media of albedo near 1 would otherwise scatter up to kMaxPathDepth times):
// true when the path ends, else its throughput carries the survivors' weight.
bool VolPathTracer::Roulette(PathState& state, float eta_scale, float u) {
    const Rgb rr = state.beta * eta_scale / state.r_u.Average();
    const float q = std::max(0.0f, 1 - std::sqrt(rr.MaxComponent()));
    if (u < q) return true;
    state.beta /= 1 - q;
    return false;
}

VolPathTracer::VolPathTracer(const EmbreeScene& scene, int max_depth, LightStrategy strategy)
    : scene_(scene), media_(scene.media()), lights_(scene, strategy), max_depth_(max_depth) {}

template <typename FromOf, typename MediumOf, typename F, typename Pdf>
Rgb VolPathTracer::SampleLight(const SurfacePoint& at, const Vec3& n, FromOf&& from_of,
                               MediumOf&& medium_of, const PathState& state, float u_pick,
                               const Vec2& u_light, MediumRng& rng, F&& f_of, Pdf&& pdf_of,
                               RenderStats& stats) const {
    const std::optional<LightSample> ls = lights_.Sample(at.p, n, u_pick, u_light, at.time);
    if (!ls || !(ls->pdf > 0)) return Rgb();
    int medium = medium_of(ls->wi);
    const Rgb f = f_of(ls->wi);
    if (f.IsBlack()) return Rgb();
    const Rgb radiance = EmissionAt(scene_, ls->point, ls->radiance);
    if (radiance.IsBlack()) return Rgb();

    // Ratio tracking through every medium between here and the light; interface surfaces are
    // crossed, any other surface blocks.
    const int hero = state.hero;
    Rgb t_ray(1.0f), r_u(1.0f), r_l(1.0f);
    Ray ray = SpawnRayTo(from_of(ls->wi), ls->point);
    for (int crossed = 0;; ++crossed) {
        if (crossed > kMaxInterfaceCrossings) return Rgb();  // degenerate interfaces: blocked
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
        if (hit &&
            scene_.scene().materials[size_t(hit->material)].type != Material::Type::kInterface) {
            return Rgb();
        }
        // Past the last surface towards a light at infinity the medium goes on for ever, as it
        // does for a ray that escapes: both strategies must see the same attenuation.
        const float t_end = hit               ? hit->t
                            : ls->at_infinity ? std::numeric_limits<float>::infinity()
                                              : ray.t_max;
        if (medium >= 0 && media_.IsHomogeneousAbsorber(medium)) {
            // Beer's law exactly: a solid's attenuation costs no noise.
            t_ray *= media_.HomogeneousTransmittance(medium, t_end * Length(ray.d));
        } else if (medium >= 0) {
            const Rgb t_maj = media_.SampleTMaj(
                medium, ray, t_end, hero, rng,
                [&](const Vec3&, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb& tm) {
                    const Rgb sigma_n = ClampZero(sigma_maj - mp.sigma_a - mp.sigma_s);
                    const float pdf = Channel(tm, hero) * Channel(sigma_maj, hero);
                    t_ray *= tm * sigma_n / pdf;
                    r_l *= tm * sigma_maj / pdf;
                    r_u *= tm * sigma_n / pdf;
                    const Rgb tr = t_ray / (r_l + r_u).Average();
                    if (tr.MaxComponent() < kShadowRouletteBelow) {
                        if (rng.Uniform() < kShadowRouletteStop) {
                            t_ray = Rgb();
                        } else {
                            t_ray /= 1 - kShadowRouletteStop;
                        }
                    }
                    return !t_ray.IsBlack();
                });
            const float th = Channel(t_maj, hero);
            if (th > 0) {
                t_ray *= t_maj / th;
                r_l *= t_maj / th;
                r_u *= t_maj / th;
            } else {
                t_ray = Rgb();
            }
        }
        if (t_ray.IsBlack()) return Rgb();
        if (!hit) break;
        medium = MediumAfter(scene_.scene(), medium, *hit, ray.d);
        ray = SpawnRayTo(HitPoint(*hit), ls->point);
    }
    r_l *= state.r_u * ls->pdf;
    r_u *= state.r_u * pdf_of(ls->wi);
    const Rgb carried = state.beta * f * t_ray * radiance;
    return ls->delta ? carried / r_l.Average() : carried / (r_l + r_u).Average();
}

Rgb VolPathTracer::SampleSurfaceLight(const SurfaceHit& hit, const Shading& sh, const Vec3& d,
                                      const Bsdf& bsdf, int medium, const PathState& state,
                                      float u_pick, const Vec2& u_light, MediumRng& rng,
                                      RenderStats& stats) const {
    const Frame frame = Frame::FromNormal(sh.ns);
    const Vec3 wo = frame.ToLocal(-d);
    return SampleLight(
        sh.point, sh.ns, [&](const Vec3& wi_world) { return sh.Leaving(wi_world); },
        [&](const Vec3& wi_world) {
            return frame.ToLocal(wi_world).z * wo.z < 0
                       ? MediumAfter(scene_.scene(), medium, hit, wi_world)
                       : medium;
        },
        state, u_pick, u_light, rng,
        [&](const Vec3& wi_world) {
            const Vec3 wi = frame.ToLocal(wi_world);
            if (!sh.SidesAgree(-d, wi_world, wi.z * wo.z > 0)) return Rgb();
            return bsdf.Eval(wo, wi) * std::abs(wi.z);
        },
        [&](const Vec3& wi_world) { return bsdf.Pdf(wo, frame.ToLocal(wi_world)); }, stats);
}

Rgb VolPathTracer::Li(const Ray& camera_ray, Sampler& sampler, RenderStats& stats) const {
    PathState state;
    // The hero channel: each of the three with probability 1/3, the one-sample MIS the
    // estimate's division by the rescaled densities' average completes.
    state.hero = std::min(2, int(sampler.Get1D() * 3));
    return Trace(camera_ray, PathStart{0, scene_.scene().camera_medium}, state, sampler, stats);
}

std::optional<Rgb> VolPathTracer::Irradiance(const Ray& camera_ray, Sampler& sampler,
                                             RenderStats& stats) const {
    const Scene& scene = scene_.scene();
    PathState state;
    state.hero = std::min(2, int(sampler.Get1D() * 3));
    const Vec2 u_choice = sampler.Get2D(), u_light = sampler.Get2D(), u_bsdf = sampler.Get2D();
    MediumRng rng(WalkSeed(sampler.Get2D(), 0));
    Ray ray = camera_ray;
    int medium = scene.camera_medium;
    std::optional<SurfaceHit> hit;
    for (int crossed = 0;; ++crossed) {
        if (crossed > kMaxInterfaceCrossings) return Rgb(0);
        ++stats.rays;
        hit = scene_.Intersect(ray);
        if (!hit) return Rgb(0);
        if (scene.materials[size_t(hit->material)].type != Material::Type::kInterface) break;
        medium = MediumAfter(scene, medium, *hit, ray.d);
        ray = SpawnRay(HitPoint(*hit), ray.d);
    }
    const Shading sh = Shade(scene_, *hit, -ray.d);
    const Bsdf lambert = IrradianceBsdf();
    const Frame frame = Frame::FromNormal(sh.ns);
    const Vec3 wo = frame.ToLocal(-ray.d);
    Rgb reflected = SampleSurfaceLight(*hit, sh, ray.d, lambert, medium, state, u_choice.x, u_light,
                                       rng, stats);
    const std::optional<BsdfSample> bs = lambert.Sample(wo, u_choice.y, u_bsdf);
    if (max_depth_ != 0 && bs && bs->pdf > 0) {
        const Vec3 wi = frame.FromLocal(bs->wi);
        if (sh.SidesAgree(-ray.d, wi, bs->wi.z * wo.z > 0)) {
            state.beta *= bs->f * (std::abs(bs->wi.z) / bs->pdf);
            state.r_l = state.r_u / bs->pdf;
            reflected += Trace(SpawnRay(sh.Leaving(wi), wi),
                               PathStart{1, medium, false, hit->p, sh.ns}, state, sampler, stats);
        }
    }
    return reflected * std::numbers::pi_v<float>;
}

Rgb VolPathTracer::Trace(const Ray& first_ray, const PathStart& start, PathState& state,
                         Sampler& sampler, RenderStats& stats) const {
    const Scene& scene = scene_.scene();
    Rgb L(0);
    const int hero = state.hero;
    Ray ray = first_ray;
    int medium = start.medium;
    bool specular_bounce = start.specular_bounce;  // a camera ray sees emission with full weight
    // The last scattering vertex: n zero in a medium.
    Vec3 prev_p = start.prev_p, prev_n = start.prev_n;
    float eta_scale = 1;
    int crossings = 0;  // interface surfaces this path has passed (kMaxInterfaceCrossings)
    const int max_depth = max_depth_ < 0 ? kMaxPathDepth : max_depth_;

    for (int depth = start.depth;;) {
        // As PathTracer's bounce: the same draws in the same order whatever happens, and one
        // more pair seeding the walk through a medium.
        const Vec2 u_choice = sampler.Get2D(), u_light = sampler.Get2D(), u_bsdf = sampler.Get2D();
        const float u_roulette = sampler.Get1D();
        MediumRng rng(WalkSeed(sampler.Get2D(), depth));
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);

        if (medium >= 0 && media_.IsHomogeneousAbsorber(medium)) {
            // Beer's law exactly (all channels alike: the hero's choice does not enter).
            state.beta *= media_.HomogeneousTransmittance(
                medium, hit ? hit->t * Length(ray.d) : std::numeric_limits<float>::infinity());
            if (state.beta.IsBlack()) break;
        } else if (medium >= 0) {
            bool scattered = false, terminated = false;
            const float t_end = hit ? hit->t : std::numeric_limits<float>::infinity();
            const Rgb t_maj = media_.SampleTMaj(
                medium, ray, t_end, hero, rng,
                [&](const Vec3& p, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb& tm) {
                    const float maj = Channel(sigma_maj, hero), tmh = Channel(tm, hero);
                    // Emission, the source term sigma_a Le, at every tentative collision.
                    if (depth < max_depth && !mp.Le.IsBlack()) {
                        const float pdf = maj * tmh;
                        const Rgb r_e = state.r_u * sigma_maj * tm / pdf;
                        if (!r_e.IsBlack()) {
                            L += state.beta * tm / pdf * mp.sigma_a * mp.Le / r_e.Average();
                        }
                    }
                    const float p_absorb = Channel(mp.sigma_a, hero) / maj;
                    const float p_scatter = Channel(mp.sigma_s, hero) / maj;
                    const float u = rng.Uniform();
                    if (u < p_absorb) {
                        terminated = true;
                        return false;
                    }
                    if (u < p_absorb + p_scatter) {
                        if (depth++ >= max_depth) {
                            if (max_depth_ < 0) ++stats.truncated_paths;
                            terminated = true;
                            return false;
                        }
                        const float pdf = tmh * Channel(mp.sigma_s, hero);
                        state.beta *= tm * mp.sigma_s / pdf;
                        state.r_u *= tm * mp.sigma_s / pdf;
                        if (state.beta.IsBlack() || state.r_u.IsBlack()) {
                            terminated = true;
                            return false;
                        }
                        const float g = media_.g(medium);
                        const Vec3 d = Normalize(ray.d);
                        const SurfacePoint here = PointInMedium(p, ray.time);
                        L += SampleLight(
                            here, Vec3(), [&](const Vec3&) { return here; },
                            [&](const Vec3&) { return medium; }, state, u_choice.x, u_light, rng,
                            [&](const Vec3& wi) { return Rgb(HenyeyGreenstein(Dot(d, wi), g)); },
                            [&](const Vec3& wi) { return HenyeyGreenstein(Dot(d, wi), g); }, stats);
                        const PhaseSample ps = SampleHenyeyGreenstein(d, g, u_bsdf);
                        if (!(ps.pdf > 0)) {
                            terminated = true;
                            return false;
                        }
                        if (depth > kRouletteStartDepth && Roulette(state, eta_scale, u_roulette)) {
                            terminated = true;
                            return false;
                        }
                        // The phase function is sampled exactly: beta keeps its value.
                        state.r_l = state.r_u / ps.pdf;
                        prev_p = p;
                        prev_n = Vec3();
                        specular_bounce = false;
                        ray = SpawnRay(here, ps.wi);
                        scattered = true;
                        return false;
                    }
                    // A null collision: the walk goes on, reweighted.
                    const Rgb sigma_n = ClampZero(sigma_maj - mp.sigma_a - mp.sigma_s);
                    const float pdf = tmh * Channel(sigma_n, hero);
                    if (!(pdf > 0)) {
                        terminated = true;
                        return false;
                    }
                    state.beta *= tm * sigma_n / pdf;
                    state.r_u *= tm * sigma_n / pdf;
                    state.r_l *= tm * sigma_maj / pdf;
                    return !state.beta.IsBlack() && !state.r_u.IsBlack();
                });
            if (terminated || state.beta.IsBlack() || state.r_u.IsBlack()) break;
            if (scattered) continue;
            const float th = Channel(t_maj, hero);
            if (!(th > 0)) break;
            state.beta *= t_maj / th;
            state.r_u *= t_maj / th;
            state.r_l *= t_maj / th;
        }

        if (!hit) {
            // Lights at infinity: the sky and sun disks.
            const Vec3 w = Normalize(ray.d);
            const Rgb le = lights_.EscapedRadiance(w);
            if (!le.IsBlack()) {
                if (specular_bounce) {
                    L += state.beta * le / state.r_u.Average();
                } else {
                    const Rgb r_l = state.r_l * lights_.EscapedPdf(w);
                    L += state.beta * le / (state.r_u + r_l).Average();
                }
            }
            break;
        }
        const Material& material = scene.materials[size_t(hit->material)];
        if (material.type == Material::Type::kInterface) {
            // Neither a bounce nor a scattering event: the ray goes on into the other medium.
            if (++crossings > kMaxInterfaceCrossings) break;
            medium = MediumAfter(scene, medium, *hit, ray.d);
            ray = SpawnRay(HitPoint(*hit), ray.d);
            continue;
        }
        const Vec3& ng = hit->n;
        const float cos_o_ng = -Dot(ray.d, ng);
        const Shading sh = Shade(scene_, *hit, -ray.d);
        if ((cos_o_ng > 0 || EmitsFromBack(material)) && !sh.emission.IsBlack()) {
            if (specular_bounce) {
                L += state.beta * sh.emission / state.r_u.Average();
            } else {
                const Rgb r_l = state.r_l * lights_.Pdf(prev_p, prev_n, *hit);
                L += state.beta * sh.emission / (state.r_u + r_l).Average();
            }
        }
        if (depth++ >= max_depth) {
            if (max_depth_ < 0) ++stats.truncated_paths;
            break;
        }

        const Frame frame = Frame::FromNormal(sh.ns);
        const Vec3 wo = frame.ToLocal(-ray.d);
        const Bsdf bsdf(material, sh.params);
        if (!bsdf.IsDelta()) {
            L += SampleSurfaceLight(*hit, sh, ray.d, bsdf, medium, state, u_choice.x, u_light, rng,
                                    stats);
        }
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, u_choice.y, u_bsdf);
        if (!bs || !(bs->pdf > 0)) break;
        const Vec3 wi = frame.FromLocal(bs->wi);
        if (!sh.SidesAgree(-ray.d, wi, bs->wi.z * wo.z > 0)) break;
        state.beta *= bs->f * (std::abs(bs->wi.z) / bs->pdf);
        if (state.beta.IsBlack()) break;
        // A delta lobe's density cancels in beta; light sampling cannot make its direction.
        state.r_l = bs->delta ? state.r_u : state.r_u / bs->pdf;
        specular_bounce = bs->delta;
        eta_scale *= bs->eta * bs->eta;
        if (bs->wi.z * wo.z < 0) medium = MediumAfter(scene, medium, *hit, wi);
        prev_p = hit->p;
        prev_n = sh.ns;
        ray = SpawnRay(sh.Leaving(wi), wi);

        if (depth > kRouletteStartDepth && Roulette(state, eta_scale, u_roulette)) break;
    }
    return L;
}

}  // namespace lf
