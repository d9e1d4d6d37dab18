#include "lf/kernels/light_tracer.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "lf/kernels/bsdf.h"
#include "lf/kernels/next_event.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/shading.h"
#include "tbb/parallel_for.h"

namespace lf {

namespace {

// As the path tracer: roulette spares the first bounce.
constexpr int kRouletteStartDepth = 1;

}  // namespace

LightTracer::LightTracer(const EmbreeScene& scene, const Camera& camera,
                         const SplatRenderSettings& settings)
    : scene_(scene), camera_(camera), settings_(settings), emission_(scene) {}

void LightTracer::Splat(const Vec2& raster, int half, Rgb value, SplatList& splats,
                        RenderStats& stats) const {
    if (!value.IsFinite()) {
        ++stats.invalid_samples;
        return;
    }
    if (value.IsBlack()) return;
    const int w = camera_.width(), h = camera_.height();
    if (settings_.clamp > 0) {
        // A splat's share of its pixel is splat x W H / N; with N = W H k paths (k per pixel)
        // that is splat / k, as a camera sample's is radiance / spp: the splat is on the scale of
        // a camera sample's radiance, so the limit is the clamp itself (BDPT's t = 1 rule).
        const double limit = settings_.clamp;
        if (value.MaxComponent() > limit) value *= float(limit / value.MaxComponent());
    }
    // Raster positions on the film's far edges may round to W or H.
    const int x = std::clamp(int(std::floor(raster.x)), 0, w - 1);
    const int y = std::clamp(int(std::floor(raster.y)), 0, h - 1);
    splats.Add(x, y, half, value);
}

void LightTracer::TracePath(uint64_t index, SplatList& splats, RenderStats& stats) const {
    const std::vector<Material>& materials = scene_.scene().materials;
    const uint64_t frame = uint64_t(camera_.width()) * uint64_t(camera_.height());
    const uint64_t j = index >> 1, q = j % frame;
    const int half = int(index & 1);
    Sampler sampler(settings_.seed, int(q % uint64_t(camera_.width())),
                    int(q / uint64_t(camera_.width())), 2 * (j / frame) + uint64_t(half),
                    settings_.sampler);
    const bool lens = camera_.HasLens();
    // The whole path, and the camera it reaches, at one time in the shutter.
    const float time = sampler.GetTime();

    const float u_pick = sampler.Get1D();
    const Vec2 u_pos = sampler.Get2D(), u_dir = sampler.Get2D();
    const std::optional<EmissionSample> es = emission_.Sample(u_pick, u_pos, u_dir, time);
    if (!es) return;
    // Power leaving y0 per path: Le |cos| / (pick pdf_pos pdf_dir). Point, spot and the lights
    // at infinity have point.n = w, so their cosine is 1.
    const float cos_light = std::abs(Dot(es->w, es->point.n));
    const Rgb power = es->le * (cos_light / (es->pick * es->pdf_pos * es->pdf_dir));

    // y0 seen directly: the emitter's radiance towards the camera, Le We |cos| / (pick pdf_pos
    // pdf_camera), when the light emits that way (its front, or either side if two-sided).
    const Vec2 u_lens0 = lens ? sampler.Get2D() : Vec2{};
    if (es->on_surface) {
        if (const auto cs = camera_.SampleWi(es->point.p, u_lens0, time);
            cs && cs->pdf > 0 && cs->we > 0 &&
            emission_.PdfLe(es->light, es->point.p, es->point.n, cs->wi, time).dir > 0) {
            const Rgb value = es->le * (std::abs(Dot(cs->wi, es->point.n)) * cs->we /
                                        (es->pick * es->pdf_pos * cs->pdf));
            ++stats.rays;
            const SurfacePoint lens_point{cs->lens_point, Vec3(), Vec3()};
            if (!scene_.Occluded(SpawnRayTo(es->point, lens_point))) {
                Splat(cs->raster, half, value, splats, stats);
            }
        }
    }
    if (settings_.max_depth == 0) return;

    Ray ray = es->ray();
    // The throughput relative to y0's power: what roulette looks at, as the path tracer's beta.
    Rgb beta(1);
    int medium = -1;  // the solid transmitter the path travels through, or -1
    for (int bounce = 0;; ++bounce) {
        // The vertex's numbers, drawn in the same order whatever happens there: the lens point
        // of its camera connection, the lobe and roulette pair, the BSDF direction.
        const Vec2 u_lens = lens ? sampler.Get2D() : Vec2{};
        const Vec2 u_choice = sampler.Get2D(), u_bsdf = sampler.Get2D();
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
        if (!hit) break;
        if (medium >= 0) {
            beta *= Attenuation(scene_, medium, hit->t * Length(ray.d));
            if (beta.IsBlack()) break;
        }
        const Material& material = materials[size_t(hit->material)];
        const Vec3& ng = hit->n;
        const Vec3 wo_world = -Normalize(ray.d);  // towards the light's side of the path
        const float cos_o_ng = std::abs(Dot(wo_world, ng));
        if (!(cos_o_ng > 0)) break;
        const Shading sh = Shade(scene_, *hit, wo_world);
        const Frame frame = Frame::FromNormal(sh.ns);
        const Vec3 wo = frame.ToLocal(wo_world);
        const Bsdf bsdf(material, sh.params);

        // y_{bounce + 1} to the camera.
        if (!bsdf.IsDelta()) {
            if (const auto cs = camera_.SampleWi(hit->p, u_lens, time);
                cs && cs->pdf > 0 && cs->we > 0) {
                const Vec3 wi = frame.ToLocal(cs->wi);
                const bool reflect = wi.z * wo.z > 0;
                if (sh.SidesAgree(wo_world, cs->wi, reflect)) {
                    const float eta = bsdf.RefractionEta(wo, wi);
                    // f* |wi . ns| with the shading-normal factor |wo . ns| |wi . ng| /
                    // (|wo . ng| |wi . ns|): the |wi . ns| cancel.
                    const float geometry =
                        eta * eta * std::abs(wo.z) * std::abs(Dot(cs->wi, ng)) / cos_o_ng;
                    Rgb value = power * beta * bsdf.Eval(wo, wi) * (geometry * cs->we / cs->pdf);
                    if (!value.IsBlack()) {
                        ++stats.rays;
                        const SurfacePoint lens_point{cs->lens_point, Vec3(), Vec3()};
                        if (!scene_.Occluded(SpawnRayTo(sh.Leaving(cs->wi), lens_point))) {
                            const int through =
                                reflect ? medium
                                        : MediumAfter(scene_.scene(), medium, *hit, cs->wi);
                            value *= Attenuation(scene_, through, Length(cs->lens_point - hit->p));
                            Splat(cs->raster, half, value, splats, stats);
                        }
                    }
                }
            }
        }
        if (bounce + 1 == settings_.max_depth) break;
        if (bounce + 1 >= kMaxPathDepth) {
            ++stats.truncated_paths;
            break;
        }

        // Onwards by sampling the adjoint BSDF: Bsdf's sample times eta^2 for refractions, and
        // the shading-normal factor.
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, u_choice.x, u_bsdf);
        if (!bs || !(bs->pdf > 0)) break;
        const Vec3 wi_world = frame.FromLocal(bs->wi);
        const bool transmitted = bs->wi.z * wo.z < 0;
        if (!sh.SidesAgree(wo_world, wi_world, !transmitted)) break;
        const float cos_i_ng = Dot(wi_world, ng);
        beta *= bs->f *
                (bs->eta * bs->eta * std::abs(wo.z) * std::abs(cos_i_ng) / (cos_o_ng * bs->pdf));
        if (beta.IsBlack() || !beta.IsFinite()) break;
        if (transmitted) medium = MediumAfter(scene_.scene(), medium, *hit, wi_world);
        ray = SpawnRay(sh.Leaving(wi_world), wi_world);

        if (bounce >= kRouletteStartDepth) {
            const float q = std::max(0.0f, 1 - beta.MaxComponent());
            if (u_choice.y < q) break;
            beta /= 1 - q;
        }
    }
}

void LightTracer::Render(const SplatWork& work, TileSums& camera, SplatList& splats,
                         const std::atomic<bool>* cancel) const {
    if (work.path_end <= work.path_begin) return;
    const uint64_t paths = work.path_end - work.path_begin;
    const uint64_t chunks = (paths + kChunkPaths - 1) / kChunkPaths;
    struct Chunk {
        SplatList splats;
        RenderStats stats;
    };
    std::vector<Chunk> results(chunks);
    tbb::parallel_for(uint64_t(0), chunks, [&](uint64_t c) {
        if (cancel && cancel->load(std::memory_order_relaxed)) return;
        Chunk& chunk = results[c];
        chunk.splats = SplatList(camera_.width(), camera_.height());
        const uint64_t begin = work.path_begin + c * kChunkPaths;
        const uint64_t end = std::min(work.path_end, begin + kChunkPaths);
        for (uint64_t i = begin; i < end; ++i) TracePath(i, chunk.splats, chunk.stats);
        chunk.stats.samples += end - begin;
        chunk.splats.Coalesce();
    });
    // In chunk order, so the list's raw entries (and the stats) do not depend on the threads.
    for (Chunk& chunk : results) {
        if (chunk.splats.width() == 0) continue;  // cancelled before it ran
        splats += chunk.splats;
        camera.stats += chunk.stats;
    }
}

}  // namespace lf
