#include "lf/kernels/path_tracer.h"

#include <algorithm>

#include "lf/kernels/bsdf.h"

namespace lf {

namespace {

float PowerHeuristic(float pdf_a, float pdf_b) {
    const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    if (std::isinf(a)) return 1;
    return a + b > 0 ? a / (a + b) : 0;
}

SurfacePoint AsPoint(const SurfaceHit& hit) { return {hit.p, hit.p_error, hit.n}; }

// Roulette spares the first bounce: direct and one-bounce light are never cut.
constexpr int kRouletteStartDepth = 1;

}  // namespace

PathTracer::PathTracer(const EmbreeScene& scene, int max_depth)
    : scene_(scene), lights_(scene), max_depth_(max_depth) {}

Rgb PathTracer::Li(const Ray& camera_ray, Sampler& sampler, RenderStats& stats) const {
    const std::vector<Material>& materials = scene_.scene().materials;
    Rgb L(0), beta(1);
    Ray ray = camera_ray;
    bool delta_bounce = true;  // the camera ray sees emission with full weight
    float prev_pdf = 0;
    Vec3 prev_p;
    float eta_scale = 1;

    for (int depth = 0;; ++depth) {
        ++stats.rays;
        const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
        if (!hit) break;
        const Material& material = materials[size_t(hit->material)];
        const bool front = Dot(ray.d, hit->n) < 0;

        if (front && material.IsEmissive()) {
            if (delta_bounce) {
                L += beta * material.emission;
            } else {
                const float light_pdf = lights_.Pdf(prev_p, *hit);
                L += beta * material.emission * PowerHeuristic(prev_pdf, light_pdf);
            }
        }
        if (depth == max_depth_) break;
        if (depth == kMaxPathDepth) {
            ++stats.truncated_paths;
            break;
        }

        const Frame frame = Frame::FromNormal(hit->n);
        const Vec3 wo = frame.ToLocal(-ray.d);
        const Bsdf bsdf(material);
        const SurfacePoint here = AsPoint(*hit);

        if (!bsdf.IsDelta()) {
            const float u_pick = sampler.Get1D();
            const Vec2 u_light = sampler.Get2D();
            if (const auto ls = lights_.Sample(hit->p, u_pick, u_light)) {
                const Vec3 wi = frame.ToLocal(ls->wi);
                const Rgb f = bsdf.Eval(wo, wi) * std::abs(wi.z);
                if (!f.IsBlack()) {
                    ++stats.rays;
                    if (!scene_.Occluded(SpawnRayTo(here, ls->point))) {
                        const float w =
                            ls->delta ? 1.0f : PowerHeuristic(ls->pdf, bsdf.Pdf(wo, wi));
                        L += beta * f * ls->radiance * (w / ls->pdf);
                    }
                }
            }
        }

        const float uc = sampler.Get1D();
        const Vec2 u = sampler.Get2D();
        const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, u);
        if (!bs || !(bs->pdf > 0)) break;
        beta *= bs->f * (std::abs(bs->wi.z) / bs->pdf);
        if (beta.IsBlack()) break;
        if (bs->delta && bs->wi.z * wo.z < 0) {
            // Radiance is scaled by 1/eta^2 across the interface; roulette must not see that.
            const float eta = wo.z > 0 ? material.ior : 1 / material.ior;
            eta_scale *= eta * eta;
        }
        delta_bounce = bs->delta;
        prev_pdf = bs->pdf;
        prev_p = hit->p;
        const Vec3 wi = frame.FromLocal(bs->wi);
        ray = SpawnRay(here, wi);

        if (depth >= kRouletteStartDepth) {
            const float q = std::max(0.0f, 1 - beta.MaxComponent() * eta_scale);
            if (sampler.Get1D() < q) break;
            beta /= 1 - q;
        }
    }
    return L;
}

}  // namespace lf
