// Bidirectional path tracing (`--method bdpt`; Veach 1997, ch. 10, with pbrt-v4's
// BDPTIntegrator as the model). Each camera sample traces a camera subpath and a light subpath
// and joins every prefix pair (s light vertices, t camera vertices) into a full path:
//  - s = 0: the camera subpath reaches an emitter itself (area lights, and the sky and sun
//    disks when it escapes);
//  - s = 1: next-event estimation from a camera vertex with the path tracer's LightSampler
//    (lf/kernels/lights.h), its strategy and its delta lights;
//  - t = 1: a light vertex connected to the camera (Camera::SampleWi): the contribution lands
//    on whatever pixel the connection's raster position falls in, so it is splatted;
//  - s, t >= 2: a shadow ray between a light vertex and a camera vertex.
// The strategies are weighed by the power heuristic over all strategies that could have made
// the same path, computed from per-vertex forward and reverse area densities (pbrt's
// recursion). A delta lobe's density counts as 1 in projected solid angle times n^2, the measure
// specular scattering preserves, and keeps the geometry term of its segment (Veach 10.3.5; pbrt
// remaps the area density to 1, which drops it and misweighs caustics: see Walk); a delta vertex
// (or a vertex next to one, or a delta light) cannot be the end of a connection, so those
// strategies drop out of the sum. A light vertex's density is the EmissionSampler's (pick by power,
// then PdfLe) for the strategies with s >= 2, and the LightSampler's (LightSampler::Pdf,
// EscapedPdf) for s = 1, as each strategy really samples it, so the weights sum to 1 over the
// strategies that can make a path, whatever points either sampler can or cannot reach (delta
// lights: the emission pick stands for both).
//
// Light subpaths carry importance: the adjoint BSDF (no 1/eta^2 across refraction) and the
// shading-normal correction |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|) of Veach's thesis 5.3.
//
// Participating media (pbrt-v4's BDPT with medium vertices; VolPathTracer is the reference).
// Both subpaths track the medium they travel in by the shapes' MediumInterfaces: the camera
// subpath starts in Scene::camera_medium; the light subpath in the medium at its light, found
// by following the segment from the camera to the light's point through every surface on the
// way (then, for an area light whose shape has an interface, the side it emits into), which
// needs no model change and is right wherever the interfaces enclose their media consistently.
// Inside a scattering medium a subpath samples distances by delta tracking
// (SceneMedia::SampleTMaj): a real collision is absorbed (the subpath ends) or scatters into a
// medium vertex, sampled by the Henyey-Greenstein phase function and connectible like a
// surface; its densities carry no cosine. Homogeneous absorbers (solids' interiors) take Beer's
// law exactly. Interface surfaces are no vertices: walks and connections pass through them.
// A connection segment's transmittance is estimated by ratio tracking through every medium on
// the way (Beer's law through absorbers); any other surface blocks it.
// Chromatic media: a hero channel per camera sample (uniform over the three), shared by both
// subpaths, drives the distance sampling; each vertex keeps beta, its throughput over the
// hero's density, and r, the density with each channel as the hero over the hero's own. A
// strategy's estimate is divided by the mean of the two subpaths' r multiplied channel by
// channel: one-sample MIS (balance heuristic) over the choice of the hero, unbiased for every
// channel whichever hero was drawn. Ratio tracking is unbiased in every channel for any hero,
// so the connection's transmittance needs no such weight. The MIS weights over strategies
// ignore transmittance and distance densities (as pbrt-v4's): they are the same fictitious
// densities in every strategy's weight, so they still sum to 1 over the strategies that can
// make a path. Emissive media are not emitters here: lf/job/method_registry.h refuses them.
//
// Depth and roulette: max_depth counts bounces as the path tracer does: a path of s + t
// vertices has s + t - 2 bounces, and strategies with more than max_depth are not made, so the
// image converges to the path tracer's at the same max_depth (except for what the path tracer
// cannot sample: delta lights seen through mirrors and glass, i.e. their caustics). Negative
// max_depth: unlimited, each subpath capped at kBdptUnlimitedDepth bounces (cut subpaths are
// counted in truncated_paths). The cap is far below the path tracer's kMaxPathDepth because the
// connections cost (camera vertices x light vertices) shadow rays and MIS weights of length
// s + t each: in a furnace of reflectance 1, where roulette never ends a path, 65536 vertices a
// subpath made one sample run for minutes. Paths beyond 128 bounces carry rho^128 of the light
// (0.28 at rho 0.99, 2e-6 at 0.9): a bias only for nearly white closed rooms, where the path
// tracer (or a finite --max-depth) is the method. Both subpaths play Russian roulette from
// their second bounce on, the camera subpath on its throughput (times eta^2, as the path tracer),
// the light subpath on its throughput relative to the emitted one; roulette only scales
// contributions, so the weights (which ignore it) still sum to 1.
//
// Random numbers. Camera sample s of pixel (x, y) draws from Sampler(seed, x, y, s, sampler),
// in this fixed order: the film point (2D, through Camera::SampleFilm), the lens point (2D,
// only when the camera has a lens), the light subpath's emission (1D light pick, 2D position,
// 2D direction), then four draws per camera vertex (2D: next-event light pick and BSDF lobe;
// 2D next-event point; 2D BSDF direction; 1D roulette), then four per light vertex (2D lobe;
// 2D lens point of its t = 1 connection; 2D direction; 1D roulette). The hero channel and the
// tracking through media draw from a MediumRng seeded by (seed, pixel, sample), not from the
// sampler. The result is a pure function of (seed, pixel, sample): any split of the samples
// over tasks and threads gives the same sums.
//
// Where results go. The t >= 2 strategies of a sample add up to one camera sample of its pixel
// (PixelSums::Add with the sample's index); each t = 1 contribution is splatted into the
// SplatList at the pixel holding its raster position, half = the camera sample's parity, with
// pbrt's film-normalised importance: a pixel is its camera mean plus its splat sum times
// W H / N, N the camera samples of the frame (lf/job/splat_merge.h). Only the box filter is
// supported (lf::MakeSplatRenderer refuses the others): a splat goes to one pixel.
#pragma once

#include <atomic>
#include <memory>

#include "lf/core/camera.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/light_emission.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/media.h"
#include "lf/kernels/splat_renderer.h"

namespace lf {

// The most bounces of each subpath when max_depth is unlimited (see the file comment).
inline constexpr int kBdptUnlimitedDepth = 128;

struct BdptVertex;

class BdptRenderer : public SplatRenderer {
  public:
    // scene and camera must outlive the renderer. The camera's pixel filter is taken as box
    // (lf::MakeSplatRenderer refuses others).
    BdptRenderer(const EmbreeScene& scene, const Camera& camera,
                 const SplatRenderSettings& settings);
    ~BdptRenderer() override;

    // Camera samples [work.sample_begin, work.sample_end) of every pixel of work.rect; the path
    // range is unused (a sample's light subpath is its own). Rows run in parallel (tbb), each
    // into its own sums, which are then added exactly.
    void Render(const SplatWork& work, TileSums& camera, SplatList& splats,
                const std::atomic<bool>* cancel = nullptr) const override;

    // One camera sample of pixel (x, y): its t >= 2 strategies' sum (unclamped) is returned,
    // its t = 1 contributions (clamped per splat) added to `splats`. Rays cast go to stats.rays,
    // non-finite splats to stats.invalid_samples. For tests and Render.
    Rgb Sample(int x, int y, uint64_t sample_index, SplatList& splats, RenderStats& stats) const;

  private:
    struct Scratch;
    using Path = std::vector<BdptVertex>;

    struct Spectral;

    // Extends `path` (whose last vertex is where `ray` starts, in `medium`) by up to
    // `max_vertices` vertices.
    void Walk(Ray ray, Rgb beta, float pdf_fwd, int max_vertices, bool importance, int medium,
              Spectral& spectral, Sampler& sampler, Path& path, RenderStats& stats) const;
    // The light subpath of the emission numbers at `time` in the shutter (`eye`: the camera
    // vertex, whose medium is known); empty when the sample carries no light.
    void LightSubpath(float u_pick, const Vec2& u_pos, const Vec2& u_dir, float time,
                      const BdptVertex& eye, Spectral& spectral, Sampler& sampler, Path& path,
                      RenderStats& stats) const;
    // Strategy (s, t) for t >= 2 (camera sum) or t = 1 (then *raster is set when it
    // contributes); 0 when it does not apply or is occluded. Weighted.
    Rgb Connect(Path& light, Path& camera, int s, int t, Vec2* raster, Spectral& spectral,
                RenderStats& stats) const;
    float MisWeight(Path& light, Path& camera, int s, int t) const;

    // Densities (area measure at `next`, or solid angle when next is at infinity).
    float ConvertDensity(const BdptVertex& from, float pdf, const BdptVertex& next) const;
    float PdfTo(const BdptVertex& v, const BdptVertex* prev, const BdptVertex& next) const;
    float PdfLight(const BdptVertex& light, const BdptVertex& next) const;
    float PdfLightOrigin(const BdptVertex& light, const BdptVertex& next) const;
    // p_LightSampler(light | ref) / p_emission(light): how much likelier next-event estimation
    // from `ref` picks the light vertex's point than the emission sampler does (both per area,
    // per solid angle for lights at infinity); 1 for delta lights and where either is unknown.
    float NeeRatio(const BdptVertex& light, const BdptVertex& ref) const;
    // f times the cosine at v towards unit direction `dir` (importance: the adjoint BSDF and the
    // shading-normal correction).
    Rgb FCos(const BdptVertex& v, const Vec3& dir, bool importance) const;
    // The transmittance along the segment from scattering vertex `from` towards `to` through
    // interface surfaces, 0 when another surface blocks it.
    Rgb Transmission(const BdptVertex& from, const BdptVertex& to, Spectral& spectral,
                     RenderStats& stats) const;
    // Along `ray` over [0, t_end) in `medium`: Beer's law or a ratio-tracking estimate.
    Rgb SegmentTransmittance(int medium, const Ray& ray, float t_end, Spectral& spectral) const;
    // The medium a ray leaving scattering vertex v in direction dir travels through, or -1.
    int MediumToward(const BdptVertex& v, const Vec3& dir) const;
    // The medium the light subpath starting at `light` leaves into (see the file comment).
    int MediumAtLight(const BdptVertex& eye, const BdptVertex& light, RenderStats& stats) const;

    const EmbreeScene& scene_;
    const Camera& camera_;
    SplatRenderSettings settings_;
    LightSampler lights_;
    EmissionSampler emission_;
    const SceneMedia& media_;
    float infinite_pdf_pos_;  // 1 / (pi R^2): the density of the disk lights at infinity use
    bool has_infinite_;       // the scene has a sky or a sun disk that escaping rays see
    // The scene has media beyond homogeneous absorbers, interface surfaces or a camera in a
    // medium: connections cross interfaces and the light subpath looks up its medium.
    bool volumetric_ = false;
};

}  // namespace lf
