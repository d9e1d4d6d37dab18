// Light tracing (`--method light`; pbrt-v4's LightPathIntegrator, Mitsuba 3's ptracer): paths
// start on the lights (lf/kernels/light_emission.h) and every vertex that can be seen is
// connected to the camera (Camera::SampleWi) and splatted onto the film, the t = 1 strategy of
// bidirectional path tracing on its own. It excels where the path tracer struggles (caustics
// seen through or cast by specular surfaces under small lights) and cannot see what only a
// camera ray finds (mirrors and glass seen directly, and the lights at infinity as a
// background).
//
// Light path i of a job is a pure function of i and the settings: its sampler is keyed as
// lf::SplatTask says (pixel-equivalent q = (i >> 1) mod W H, sample 2 ((i >> 1) / W H) + (i & 1))
// and it splats into half i & 1, so any split of [0, N) over tasks and threads gives the same
// splat sums. Splats are in lf/job/splat_merge.h's normalisation: the image is W H / N times
// the splat sum.
//
// The path, vertex by vertex:
// - y0 on the light, throughput beta = Le |cos| / (pick pdf_pos pdf_dir). An area light's y0
//   is connected to the camera (the emitter seen directly), with weight We |cos_light| /
//   (pick pdf_pos pdf_camera); delta-position lights and the lights at infinity are not.
// - y1, y2, ...: the surfaces the path meets. At each whose BSDF is not a pure delta, a
//   shadow ray to the camera's lens adds beta f*(wo, wi) |cos| We / pdf_camera, where f* is the
//   adjoint BSDF of importance transport (below). The path goes on by sampling f*.
// - Depth: a light path of max_depth bounces connects y1 .. y_max_depth, i.e. light paths of at
//   most max_depth + 1 segments to the camera, which are exactly the paths the path tracer
//   counts with the same max_depth (its emission seen at depth d ends a path of d + 1
//   segments). max_depth 0 leaves the directly seen emitters only; negative is unlimited
//   (roulette, and kMaxPathDepth, counted in truncated_paths).
// - Roulette from the second bounce on, on the throughput relative to y0's (the path tracer's
//   rule: q = max(0, 1 - max channel)).
// - Inside solid transmitters the throughput is attenuated by Beer's law, as the path tracer's.
//
// Importance transport (Veach 1997, ch. 5; pbrt-v4's TransportMode::Importance):
// - Refraction: Bsdf divides a refracted pair by eta^2 (radiance is compressed into the denser
//   medium's smaller solid angle); a light path carries flux, which is not, so the light
//   tracer multiplies eta^2 back (Bsdf::RefractionEta). Radiance's factors cancel on a path
//   that enters and leaves a solid, but not on one that scatters inside it (a diffuse object
//   in water, a light inside glass, the inside of a rough solid seen through its surface): those
//   would be off by eta^2, and roulette would end paths inside glass for no reason.
// - Shading normals: f* (wo, wi) |wi . ns| gets the factor |wo . ns| |wi . ng| / (|wo . ng|
//   |wi . ns|) (Veach's eq. 5.17, pbrt-v3's CorrectShadingNormal), wo towards the light, wi
//   onwards: with it the light tracer converges to the path tracer's image on smooth meshes.
//
// Clamp: a splat whose largest channel exceeds settings.clamp is scaled down to it. A splat is
// on a camera sample's scale: with k light paths per pixel (N = W H k) it adds splat x W H / N
// = splat / k to its pixel, as a camera sample adds radiance / spp. Non-finite splats are dropped
// and counted in RenderStats::invalid_samples; samples counts light paths, rays every ray
// (light rays and shadow rays to the camera).
//
// Only the box pixel filter: lf::MakeSplatRenderer refuses others (a splat goes to the one pixel
// that holds its raster position). Thin-lens cameras are handled (a lens point per vertex).
#pragma once

#include "lf/core/camera.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/light_emission.h"
#include "lf/kernels/splat_renderer.h"

namespace lf {

class LightTracer : public SplatRenderer {
  public:
    // Light paths per unit of parallel work: each chunk makes its own splat list, and the
    // chunks' lists are added in order.
    static constexpr uint64_t kChunkPaths = 1024;

    // scene and camera must outlive the tracer. The camera's pixel filter is taken as box (see
    // the file comment: MakeSplatRenderer checks).
    LightTracer(const EmbreeScene& scene, const Camera& camera,
                const SplatRenderSettings& settings);

    // Traces light paths [work.path_begin, work.path_end); the camera part of `work` (rect,
    // samples) must be empty. camera.stats gets the rays and light paths.
    void Render(const SplatWork& work, TileSums& camera, SplatList& splats,
                const std::atomic<bool>* cancel = nullptr) const override;

    // Traces light path `index` alone, adding its splats to `splats` and its rays to `stats`
    // (samples excepted): what Render does per path, for tests.
    void TracePath(uint64_t index, SplatList& splats, RenderStats& stats) const;

  private:
    // Adds `value` (already weighted by We / pdf) at raster position `raster` unless it is not
    // finite; applies the clamp.
    void Splat(const Vec2& raster, int half, Rgb value, SplatList& splats,
               RenderStats& stats) const;

    const EmbreeScene& scene_;
    const Camera& camera_;
    SplatRenderSettings settings_;
    EmissionSampler emission_;
};

}  // namespace lf
