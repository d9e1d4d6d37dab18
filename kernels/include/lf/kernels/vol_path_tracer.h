// Volumetric path tracing: the path tracer for scenes with participating media (pbrt-v4's
// VolPathIntegrator). Along each segment inside a medium, tentative collisions are drawn
// against the medium's majorant (SceneMedia::SampleTMaj); each is absorbed, scattered or null
// with the probabilities sigma_a, sigma_s and sigma_n over sigma_maj of one hero channel, drawn
// uniformly per path. The other two channels follow with ratio weights, and the estimate is
// the one-sample MIS (balance heuristic) over the three hero choices: every weight is carried as
// the path's rescaled densities r_u (unidirectional) and r_l (light sampling) per channel,
// divided out as their average. So chromatic media are unbiased in every channel. Next-event
// estimation works from surface and medium vertices. Its shadow rays pass through surfaces of
// the interface material and estimate the transmittance of each medium by ratio tracking,
// and its light samples are MIS-weighted against BSDF or phase sampling.
// `path` renders with it the scenes for which Scene::HasMedia, PathTracer the others.
// Surfaces are shaded as in PathTracer. A path crosses a shape's MediumInterface when it
// transmits or passes an interface surface.
#pragma once

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/media.h"
#include "lf/kernels/radiance.h"

namespace lf {

class Bsdf;
struct Shading;

class VolPathTracer : public RadianceEstimator {
  public:
    // As PathTracer's: max_depth negative is unlimited (kMaxPathDepth).
    VolPathTracer(const EmbreeScene& scene, int max_depth,
                  LightStrategy strategy = LightStrategy::kBvh);

    Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const override;
    const EmbreeScene& geometry() const override { return scene_; }
    // As PathTracer's: a white Lambertian bounce at the first surface (through interfaces),
    // lit through the media on the side the camera sees; what the media between the camera and
    // the surface do to the camera ray is no part of the light arriving there.
    std::optional<Rgb> Irradiance(const Ray& ray, Sampler& sampler,
                                  RenderStats& stats) const override;

  private:
    struct PathState;
    // Where a path's radiance is gathered from (as PathTracer's): the camera, or a ray sampled
    // at a surface vertex at depth - 1, starting in `medium`.
    struct PathStart {
        int depth = 0;
        int medium = -1;
        bool specular_bounce = true;
        Vec3 prev_p, prev_n;
    };
    Rgb Trace(const Ray& ray, const PathStart& start, PathState& state, Sampler& sampler,
              RenderStats& stats) const;
    // Light sampled for a vertex at `at` (surface: `n` its shading normal; medium: n zero)
    // whose scattering for the light direction wi is `f_of(wi)` (BSDF times |cos|, or the phase
    // function) with density `pdf_of(wi)`, the shadow ray leaving from `from_of(wi)` in medium
    // `medium_of(wi)`; the path's throughput and r_u there in `state`.
    template <typename FromOf, typename MediumOf, typename F, typename Pdf>
    Rgb SampleLight(const SurfacePoint& at, const Vec3& n, FromOf&& from_of, MediumOf&& medium_of,
                    const PathState& state, float u_pick, const Vec2& u_light, MediumRng& rng,
                    F&& f_of, Pdf&& pdf_of, RenderStats& stats) const;
    // SampleLight for a surface vertex seen from direction -d with `bsdf` in sh.ns's shading
    // frame, the path in `medium` on that side: the light may lie on either side, and a shadow
    // ray the BSDF calls a transmission leaves through the surface into the medium beyond.
    Rgb SampleSurfaceLight(const SurfaceHit& hit, const Shading& sh, const Vec3& d,
                           const Bsdf& bsdf, int medium, const PathState& state, float u_pick,
                           const Vec2& u_light, MediumRng& rng, RenderStats& stats) const;
    static bool Roulette(PathState& state, float eta_scale, float u);

    const EmbreeScene& scene_;
    const SceneMedia& media_;
    LightSampler lights_;
    int max_depth_;
};

}  // namespace lf
