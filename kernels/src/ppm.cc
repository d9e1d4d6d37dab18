#include "lf/kernels/ppm.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/kernels/aov_tracer.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/next_event.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/shading.h"

namespace lf {

namespace {

// Photons traced per parallel chunk: enough to amortise the task, few enough to balance.
constexpr uint64_t kPhotonChunk = 4096;

// Roulette spares the first bounce, as in the path tracer.
constexpr int kRouletteStartDepth = 1;

// x rounded to 4 significant bits.
double RoundTo4Bits(double x) {
    int e = 0;
    const double m = std::frexp(x, &e);
    return std::ldexp(std::round(m * 16) / 16, e);
}

}  // namespace

std::optional<EmittedPhoton> EmitPhoton(const EmissionSampler& emission, Sampler& sampler,
                                        float time) {
    const float u_pick = sampler.Get1D();
    const Vec2 u_pos = sampler.Get2D(), u_dir = sampler.Get2D();
    if (emission.empty()) return std::nullopt;
    const std::optional<EmissionSample> s = emission.Sample(u_pick, u_pos, u_dir, time);
    if (!s) return std::nullopt;
    const float pdf = s->pick * s->pdf_pos * s->pdf_dir;
    if (!(pdf > 0)) return std::nullopt;
    // Point, spot and infinite lights set point.n = w: their cosine is 1.
    const Rgb power = s->le * (std::abs(Dot(s->point.n, s->w)) / pdf);
    if (power.IsBlack() || !power.IsFinite()) return std::nullopt;
    return EmittedPhoton{s->ray(), power};
}

double PpmRadiusRatioSquared(double alpha, uint64_t pass) {
    double ratio = 1;
    for (uint64_t i = 0; i < pass; ++i) ratio *= (double(i) + alpha) / (double(i) + 1);
    return ratio;
}

double PpmDefaultRadius(const EmbreeScene& scene, const Camera& camera) {
    constexpr int kGrid = 16;
    std::vector<double> footprints;
    for (int j = 0; j < kGrid; ++j) {
        for (int i = 0; i < kGrid; ++i) {
            const int px = int((i + 0.5) * camera.width() / kGrid);
            const int py = int((j + 0.5) * camera.height() / kGrid);
            // Through the lens's centre: the footprint of the pinhole the lens approximates.
            const Ray ray = camera.GenerateRay(px, py, 0.5f, 0.5f, Vec2{0.5f, 0.5f});
            const Ray next = camera.GenerateRay(px + 1, py, 0.5f, 0.5f, Vec2{0.5f, 0.5f});
            const std::optional<SurfaceHit> hit = scene.Intersect(ray);
            if (!hit) continue;
            const double angle = Length(Normalize(ray.d) - Normalize(next.d));
            // Orthographic rays are parallel: their footprint is the origins' spacing.
            footprints.push_back(double(hit->t) * Length(ray.d) * angle + Length(next.o - ray.o));
        }
    }
    if (footprints.empty()) {
        const auto [lo, hi] = scene.scene().Bounds();
        const double radius = Length(hi - lo) / 2;
        return radius > 0 && std::isfinite(radius) ? RoundTo4Bits(radius / 100) : 1.0;
    }
    const auto mid = footprints.begin() + ptrdiff_t(footprints.size() / 2);
    std::nth_element(footprints.begin(), mid, footprints.end());
    return RoundTo4Bits(kDefaultRadiusPixels * *mid);
}

absl::StatusOr<std::unique_ptr<PpmRenderer>> PpmRenderer::Create(
    const EmbreeScene& scene, const Camera& camera, const SplatRenderSettings& settings) {
    if (!(settings.alpha > 0 && settings.alpha < 1)) {
        return absl::InvalidArgumentError(
            absl::StrCat("ppm: alpha ", settings.alpha, " is not in (0, 1)"));
    }
    if (!(settings.initial_radius >= 0) || !std::isfinite(settings.initial_radius)) {
        return absl::InvalidArgumentError(absl::StrCat(
            "ppm: initial radius ", settings.initial_radius, " is not a finite value >= 0"));
    }
    return std::unique_ptr<PpmRenderer>(new PpmRenderer(scene, camera, settings));
}

PpmRenderer::PpmRenderer(const EmbreeScene& scene, const Camera& camera,
                         const SplatRenderSettings& settings)
    : scene_(scene),
      camera_(camera),
      settings_(settings),
      emission_(scene),
      lights_(scene, settings.light_strategy),
      initial_radius_(settings.initial_radius > 0 ? settings.initial_radius
                                                  : PpmDefaultRadius(scene, camera)),
      photons_per_pass_(settings.photons_per_pass > 0
                            ? settings.photons_per_pass
                            : uint64_t(camera.width()) * uint64_t(camera.height())) {}

float PpmRenderer::PassTime(uint64_t pass) const {
    // The pass is the sample index of one shared pixel: Sobol stratifies the passes' times.
    return Sampler(MixBits(settings_.seed ^ kPassTimeSalt), 0, 0, pass, settings_.sampler)
        .GetTime();
}

float PpmRenderer::Radius(uint64_t pass) const {
    return float(initial_radius_ * std::sqrt(PpmRadiusRatioSquared(settings_.alpha, pass)));
}

void PpmRenderer::TraceRange(uint64_t pass, uint64_t begin, uint64_t end, std::vector<Photon>& out,
                             RenderStats& stats) const {
    const std::vector<Material>& materials = scene_.scene().materials;
    const int max_depth = settings_.max_depth;
    const uint64_t photon_seed = MixBits(settings_.seed ^ kPhotonSeedSalt);
    const float time = PassTime(pass);
    for (uint64_t i = begin; i < end; ++i) {
        Sampler sampler(photon_seed, int(i & 0xffff), int(i >> 16), pass, settings_.sampler);
        const std::optional<EmittedPhoton> emitted = EmitPhoton(emission_, sampler, time);
        if (!emitted) continue;
        Ray ray = emitted->ray;
        Rgb beta = emitted->power;
        const float emitted_max = beta.MaxComponent();
        int medium = -1;
        // depth: the photon's scattering events so far; its hit `depth` is stored when the
        // camera can reach it within max_depth (c = 0: 1 + depth <= max_depth).
        for (int depth = 0;; ++depth) {
            const float u_lobe = sampler.Get1D();
            const Vec2 u_bsdf = sampler.Get2D();
            const float u_roulette = sampler.Get1D();
            ++stats.rays;
            const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
            if (!hit) break;
            if (medium >= 0) {
                beta *= Attenuation(scene_, medium, hit->t * Length(ray.d));
                if (beta.IsBlack()) break;
            }
            const Material& material = materials[size_t(hit->material)];
            const Vec3 wo_world = -Normalize(ray.d);
            const Shading sh = Shade(scene_, *hit, wo_world);
            const Bsdf bsdf(material, sh.params);
            if (!bsdf.IsDelta() && depth >= 1) out.push_back({hit->p, wo_world, beta, depth});
            if (max_depth >= 0 && depth + 1 >= max_depth) break;
            if (depth == kMaxPathDepth) {
                ++stats.truncated_paths;
                break;
            }
            const Frame frame = Frame::FromNormal(sh.ns);
            const Vec3 wo = frame.ToLocal(wo_world);
            const std::optional<BsdfSample> bs = bsdf.Sample(wo, u_lobe, u_bsdf);
            if (!bs || !(bs->pdf > 0)) break;
            const Vec3 wi = frame.FromLocal(bs->wi);
            if (!sh.SidesAgree(wo_world, wi, bs->wi.z * wo.z > 0)) break;
            // Importance transport: the BSDF's 1/eta^2 belongs to radiance, not to flux; and
            // the adjoint BSDF of shading normals (Veach 1997, 5.3):
            // f |wi.ns| |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|).
            const float cos_o_ng = std::abs(Dot(wo_world, hit->n));
            const float cos_i_ng = std::abs(Dot(wi, hit->n));
            if (!(cos_o_ng > 0)) break;
            beta *= bs->f * (std::abs(wo.z) * cos_i_ng / (cos_o_ng * bs->pdf) * bs->eta * bs->eta);
            if (beta.IsBlack() || !beta.IsFinite()) break;
            if (bs->wi.z * wo.z < 0) medium = MediumAfter(scene_.scene(), medium, *hit, wi);
            ray = SpawnRay(sh.Leaving(wi), wi);
            if (depth >= kRouletteStartDepth) {
                const float q = std::max(0.0f, 1 - beta.MaxComponent() / emitted_max);
                if (u_roulette < q) break;
                beta /= 1 - q;
            }
        }
    }
}

PhotonMap PpmRenderer::TracePhotons(uint64_t pass, RenderStats& stats,
                                    const std::atomic<bool>* cancel) const {
    const uint64_t n = photons_per_pass_;
    const size_t chunks = size_t((n + kPhotonChunk - 1) / kPhotonChunk);
    std::vector<std::vector<Photon>> parts(chunks);
    std::vector<RenderStats> part_stats(chunks);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, chunks, 1), [&](const tbb::blocked_range<size_t>& range) {
            for (size_t c = range.begin(); c != range.end(); ++c) {
                if (cancel && cancel->load(std::memory_order_relaxed)) return;
                const uint64_t begin = c * kPhotonChunk;
                TraceRange(pass, begin, std::min(n, begin + kPhotonChunk), parts[c], part_stats[c]);
            }
        });
    size_t total = 0;
    for (const std::vector<Photon>& part : parts) total += part.size();
    std::vector<Photon> photons;
    photons.reserve(total);
    for (size_t c = 0; c < chunks; ++c) {
        photons.insert(photons.end(), parts[c].begin(), parts[c].end());
        stats += part_stats[c];
    }
    return PhotonMap(std::move(photons), Radius(pass));
}

Rgb PpmRenderer::Li(const Ray& camera_ray, const PhotonMap& map, Sampler& sampler,
                    RenderStats& stats) const {
    const std::vector<Material>& materials = scene_.scene().materials;
    const int max_depth = settings_.max_depth;
    const float radius = map.radius();
    const float density_scale =
        float(1 / (std::numbers::pi * double(radius) * radius * double(photons_per_pass_)));
    Rgb L(0), beta(1);
    Ray ray = camera_ray;
    float eta_scale = 1;
    int medium = -1;
    for (int depth = 0;; ++depth) {
        // The same dimensions at every vertex, whatever happens there (as the path tracer).
        const Vec2 u_choice = sampler.Get2D(), u_light = sampler.Get2D(), u_bsdf = sampler.Get2D();
        const float u_roulette = sampler.Get1D();
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
        if (!hit) {
            // Every vertex so far was a delta bounce: the sky counts with full weight.
            L += beta * lights_.EscapedRadiance(Normalize(ray.d));
            break;
        }
        if (medium >= 0) {
            beta *= Attenuation(scene_, medium, hit->t * Length(ray.d));
            if (beta.IsBlack()) break;
        }
        const Material& material = materials[size_t(hit->material)];
        const Vec3& ng = hit->n;
        const Vec3 wo_world = -Normalize(ray.d);
        const Shading sh = Shade(scene_, *hit, wo_world);
        if ((Dot(wo_world, ng) > 0 || EmitsFromBack(material)) && !sh.emission.IsBlack()) {
            L += beta * sh.emission;
        }
        if (depth == max_depth) break;
        if (depth == kMaxPathDepth) {
            ++stats.truncated_paths;
            break;
        }
        const Frame frame = Frame::FromNormal(sh.ns);
        const Vec3 wo = frame.ToLocal(wo_world);
        const Bsdf bsdf(material, sh.params);

        // One BSDF sample: at a delta vertex the lobe to follow; elsewhere direct light's
        // MIS sample, or one of the delta lobes of a smooth surface over a diffuse base.
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, u_choice.y, u_bsdf);
        if (!bsdf.IsDelta()) {
            // Direct light: the photons hold none (they are stored from their second hit on).
            L += beta *
                 DirectLight(*hit, sh, wo_world, bsdf, bs, medium, u_choice.x, u_light, stats);
            // Indirect light: the density estimate, over photons whose path fits in max_depth.
            const int max_photon_depth = max_depth < 0 ? kMaxPathDepth : max_depth - 1 - depth;
            Rgb sum(0);
            map.ForEachWithin(hit->p, [&](const Photon& photon) {
                if (photon.depth > max_photon_depth) return;
                const Vec3 wi = frame.ToLocal(photon.wi);
                if (!sh.SidesAgree(wo_world, photon.wi, wi.z * wo.z > 0)) return;
                sum += bsdf.Eval(wo, wi) * photon.power;
            });
            L += beta * sum * density_scale;
            // The density estimate and direct light cover the lobes that are not deltas; the
            // path goes on only along a delta lobe that was picked (weight over its
            // probability), whose next hit counts the emission it sees.
            if (!bs || !bs->delta) break;
        }

        // A delta lobe: follow it, as the path tracer.
        if (!bs || !(bs->pdf > 0)) break;
        const Vec3 wi = frame.FromLocal(bs->wi);
        if (!sh.SidesAgree(wo_world, wi, bs->wi.z * wo.z > 0)) break;
        beta *= bs->f * (std::abs(bs->wi.z) / bs->pdf);
        if (beta.IsBlack()) break;
        if (bs->wi.z * wo.z < 0) medium = MediumAfter(scene_.scene(), medium, *hit, wi);
        eta_scale *= bs->eta * bs->eta;
        ray = SpawnRay(sh.Leaving(wi), wi);
        if (depth >= kRouletteStartDepth) {
            const float q = std::max(0.0f, 1 - beta.MaxComponent() * eta_scale);
            if (u_roulette < q) break;
            beta /= 1 - q;
        }
    }
    return L;
}

// One light sample and one BSDF sample combined by the power heuristic, as the path tracer's
// first bounce: the light sampler alone would miss what it cannot sample (it gives density 0
// there, e.g. a sphere light seen from a point on that sphere), and glossy lobes are sampled
// better by the BSDF.
Rgb PpmRenderer::DirectLight(const SurfaceHit& hit, const Shading& sh, const Vec3& wo_world,
                             const Bsdf& bsdf, const std::optional<BsdfSample>& bs, int medium,
                             float u_pick, const Vec2& u_light, RenderStats& stats) const {
    const std::vector<Material>& materials = scene_.scene().materials;
    const Frame frame = Frame::FromNormal(sh.ns);
    const Vec3 wo = frame.ToLocal(wo_world);
    Rgb L = NextEventEstimate(scene_, lights_, hit, sh, wo_world, bsdf, medium, Rgb(1.0f), u_pick,
                              u_light, stats);
    // Beer's law when the BSDF sample reaches an emitter through a solid's interior.
    auto transmittance = [&](const Vec3& w, bool transmitted, float distance) {
        return Attenuation(
            scene_, transmitted ? MediumAfter(scene_.scene(), medium, hit, w) : medium, distance);
    };
    // A delta lobe's sample is the path's next segment (Li), which counts what it hits.
    if (!bs || bs->delta || !(bs->pdf > 0)) return L;
    const Vec3 wi = frame.FromLocal(bs->wi);
    if (!sh.SidesAgree(wo_world, wi, bs->wi.z * wo.z > 0)) return L;
    const Rgb weight = bs->f * (std::abs(bs->wi.z) / bs->pdf);
    if (weight.IsBlack()) return L;
    const Ray ray = SpawnRay(sh.Leaving(wi), wi);
    ++stats.rays;
    const std::optional<SurfaceHit> light_hit = scene_.Intersect(ray);
    if (!light_hit) {
        const Rgb le = lights_.EscapedRadiance(wi);
        if (!le.IsBlack()) {
            L += weight * le * PowerHeuristic(bs->pdf, lights_.EscapedPdf(wi));
        }
        return L;
    }
    const Material& light_material = materials[size_t(light_hit->material)];
    if (!(Dot(wi, light_hit->n) < 0 || EmitsFromBack(light_material))) return L;
    const Shading light_sh = Shade(scene_, *light_hit, -wi);
    if (light_sh.emission.IsBlack()) return L;
    const float w = PowerHeuristic(bs->pdf, lights_.Pdf(hit.p, sh.ns, *light_hit));
    L += weight * light_sh.emission * w *
         transmittance(wi, bs->wi.z * wo.z < 0, light_hit->t * Length(ray.d));
    return L;
}

void PpmRenderer::Render(const SplatWork& work, TileSums& camera, SplatList& /*splats*/,
                         const std::atomic<bool>* cancel) const {
    const PixelRect& rect = work.rect;
    if (rect.Area() == 0) return;
    for (uint64_t pass = work.sample_begin; pass < work.sample_end; ++pass) {
        if (cancel && cancel->load(std::memory_order_relaxed)) return;
        const PhotonMap map = TracePhotons(pass, camera.stats, cancel);
        const float time = PassTime(pass);
        std::vector<RenderStats> row_stats(size_t(rect.height));
        tbb::parallel_for(0, rect.height, [&](int row) {
            if (cancel && cancel->load(std::memory_order_relaxed)) return;
            const int y = rect.y0 + row;
            RenderStats& stats = row_stats[size_t(row)];
            for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
                Sampler sampler(settings_.seed, x, y, pass, settings_.sampler);
                const Vec2 film = camera_.SampleFilm(sampler.Get2D());
                const Vec2 lens = camera_.HasLens() ? sampler.Get2D() : Vec2{};
                const Ray ray = camera_.GenerateRay(x, y, film.x, film.y, lens, time);
                Rgb L = Li(ray, map, sampler, stats);
                if (!L.IsFinite()) {
                    ++stats.invalid_samples;
                    L = Rgb(0);
                }
                if (settings_.clamp > 0 && L.MaxComponent() > settings_.clamp) {
                    L *= float(settings_.clamp / L.MaxComponent());
                }
                camera.at(x, y).Add(pass, L);
                if (camera.aovs != 0) {
                    ++stats.rays;
                    if (const std::optional<FirstHit> first = TraceFirstHit(scene_, ray)) {
                        camera.aov_pixels[camera.Index(x, y)].Add(camera.aovs, *first);
                    }
                }
            }
            stats.samples += uint64_t(rect.width);
        });
        for (const RenderStats& s : row_stats) camera.stats += s;
    }
}

}  // namespace lf
