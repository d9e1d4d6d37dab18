// Whitted ray tracing (Whitted 1980; Heckbert's L D? S* E paths): the path tracer's special case
// without diffuse interreflection. At a surface that is not a perfect specular one (Lambertian,
// glossy, principled) a Whitted ray takes direct light only and ends there: a shadow ray to every
// delta light (point, spot, directional), and one next-event estimate from the LightSampler for
// the others (area lights, sun disks and the environment: a shadow ray to a sampled point,
// weight 1 / pdf, no MIS since no BSDF-sampled ray competes). At a mirror or dielectric (a delta
// BSDF) it follows every lobe with its weight instead of choosing one: the reflection and, for
// dielectrics, the refraction, weighted by Fresnel, up to max_depth. A smooth principled surface
// over a diffuse base has both kinds: it takes direct light for its base and follows one of its
// delta lobes, picked at random with its weight over the pick's probability. Emitters seen directly
// or through specular chains and the lights at infinity that camera and specular rays escape to add
// their radiance.
//
// What it misses, by Heckbert's notation: every path with a diffuse or glossy vertex that is not
// the one next to the light (L D D+ (S|D)* E: interreflection, colour bleeding, indirect light in
// a room) and every caustic (L S+ D ...: light through glass or off a mirror onto a diffuse
// surface). Where those terms vanish it converges to the path tracer's image at the same
// max_depth; elsewhere it is a fast, low-noise preview (docs/rendering.md).
#pragma once

#include <string>
#include <vector>

#include "lf/core/scene.h"
#include "lf/kernels/bsdf_sample.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/radiance.h"
#include "lf/kernels/shading.h"

namespace lf {

// The specular depth of an "unlimited" Whitted render. Splitting at dielectrics doubles the rays
// at each level, so the depth is bounded like pbrt-v4's Whitted integrator (maxdepth 5 there);
// rays the cap cuts are counted in RenderStats::truncated_paths.
inline constexpr int kWhittedUnlimitedDepth = 8;

class WhittedTracer : public RadianceEstimator {
  public:
    // max_depth: the most specular bounces (hits after the first) a ray tree may take; negative
    // means kWhittedUnlimitedDepth. strategy: how next-event estimation picks and samples
    // lights, as in the path tracer.
    WhittedTracer(const EmbreeScene& scene, int max_depth,
                  LightStrategy strategy = LightStrategy::kBvh);

    Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const override;
    const EmbreeScene& geometry() const override { return scene_; }

  private:
    // The radiance along `ray`, the ray tree's level `depth`, travelling inside solid transmitter
    // `medium` (a material index) or -1.
    Rgb Trace(const Ray& ray, int depth, int medium, Sampler& sampler, RenderStats& stats) const;
    // Traces the delta lobe `lobe` of the BSDF at `hit` (wo in its shading frame) and returns
    // its radiance times `weight`.
    Rgb Follow(const Ray& ray, const SurfaceHit& hit, const Shading& sh, const Material& material,
               const Vec3& wo, const BsdfSample& lobe, const Rgb& weight, int depth, int medium,
               Sampler& sampler, RenderStats& stats) const;

    const EmbreeScene& scene_;
    LightSampler lights_;
    int max_depth_;
    bool unlimited_;
    std::vector<size_t> delta_lights_;  // the LightSampler's delta lights, summed at every hit
};

// The light transport a Whitted render of `scene` leaves out, one phrase per kind, each naming
// its paths in Heckbert's notation; empty when Whitted is exact for the scene (it then converges
// to the path tracer's image at the same depth). The rule, decided from the scene description
// without tracing rays, so it errs towards naming a term the geometry might not produce:
// - interreflection (L D D+ S* E): a non-specular surface (Lambertian with a non-black albedo,
//   glossy, principled) may see another one: unless all of them are one plane or one sphere
//   (neither sees itself), it is missed, so a closed room is never exact;
// - caustics (L S+ D S* E): a mirror or dielectric may send light onto a non-specular surface:
//   missed whenever the scene has both.
std::vector<std::string> WhittedMissingTerms(const Scene& scene);

}  // namespace lf
