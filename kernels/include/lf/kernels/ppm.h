// Progressive photon mapping, probabilistic form (Knaus & Zwicker 2011): pass p traces its own
// photon map with radius r_p from the global schedule r_{p+1}^2 = r_p^2 (p + alpha) / (p + 1),
// and estimates each pixel with that pixel's camera sample p; the image is the average of the
// passes. Every pass is independent of the others, so passes split over tasks and machines
// freely (lf/job/splat_plan.h, SplatPlanKind::kPhotonPasses); the A/B halves of a pixel are
// its even and odd passes. Bias after N passes falls as r_N^2 ~ r_0^2 N^(alpha - 1)
// (docs/rendering.md, "Progressive photon mapping").
//
// A pass:
// - Photons: settings.photons_per_pass rays from EmissionSampler (a light by power, then its
//   emitted ray), power Le |cos| / pdf. They scatter by BSDF sampling with importance-transport
//   weights: no 1/eta^2 at refractions (the BSDF's radiance factor is undone) and Veach's
//   adjoint correction for shading normals; inside solid transmitters Beer's law as in the path
//   tracer; Russian roulette on the throughput relative to the emitted power. A photon is stored
//   at every non-delta surface it reaches after its first bounce: direct light is estimated at
//   the camera vertex instead, as pbrt-v4's SPPM does.
// - Camera: sample p of pixel (x, y) follows delta bounces (mirrors, dielectrics) to the first
//   non-delta vertex, or escapes. L = emission seen along the way (and the lights at infinity
//   on escape) + direct light there (one LightSampler sample and one BSDF sample, combined
//   by the power heuristic as the path tracer's first bounce) + the density estimate
//   sum f(wo, wi_photon) Phi_photon / (pi r_p^2 N_emitted) over the photons within r_p. Glossy
//   surfaces gather too, with the BSDF evaluated.
// Path lengths match the path tracer's max_depth: a photon that scattered k times before
// reaching a camera vertex found after c delta bounces counts when c + 1 + k <= max_depth.
//
// Random numbers: camera sample p of pixel (x, y) draws from Sampler(seed, x, y, p) as the path
// tracer's tiles do. Photon i of pass p draws from Sampler(MixBits(seed ^ kPhotonSeedSalt),
// i mod 2^16, i / 2^16, p): its key hashes a different seed, so its numbers are independent of
// every camera sample's (equal keys need a 64-bit hash collision), and every tile of a pass
// rebuilds the same photon map. With Sobol, photon i walks one scrambled sequence over the
// passes (stratified across passes), while the photons of a pass are independent of each other.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

#include "absl/status/statusor.h"
#include "lf/core/camera.h"
#include "lf/kernels/bsdf_sample.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/light_emission.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/photon_map.h"
#include "lf/kernels/shading.h"
#include "lf/kernels/splat_renderer.h"

namespace lf {

inline constexpr uint64_t kPhotonSeedSalt = 0x70686f746f6e73ULL;  // "photons"
// Pass p's time in the shutter: Sampler(MixBits(seed ^ kPassTimeSalt), 0, 0, p).GetTime().
inline constexpr uint64_t kPassTimeSalt = 0x73687574746572ULL;  // "shutter"
// The default r_0 in pixel footprints at the scene's typical depth (see PpmDefaultRadius).
inline constexpr double kDefaultRadiusPixels = 3;

// A photon leaving a light: the ray and the flux it carries, Le |cos| / (pick pdf_pos pdf_dir),
// so that the mean over emitted photons (failed samples counting 0) is the lights' total power.
struct EmittedPhoton {
    Ray ray;
    Rgb power;
};
// Draws u_pick, u_pos, u_dir from `sampler`, in that order; nullopt when the sample carries no
// light. The photon leaves at `time` in the shutter.
std::optional<EmittedPhoton> EmitPhoton(const EmissionSampler& emission, Sampler& sampler,
                                        float time = 0);

// r_p^2 / r_0^2 = prod_{i < p} (i + alpha) / (i + 1), by that product in double.
double PpmRadiusRatioSquared(double alpha, uint64_t pass);

// The r_0 used when settings.initial_radius is 0: kDefaultRadiusPixels times the median, over a
// 16 x 16 grid of pixel centres, of the camera-ray hit distance times the angle between
// neighbouring pixels' rays (the pixel's footprint there); rounded to 4 significant bits so
// that machines whose Embree builds differ in the last bit of a distance agree on it. When no
// ray hits, 1/100 of the scene's bounding-sphere radius (1 for an empty scene). The farm
// should resolve it once at planning time and pass it as initial_radius.
double PpmDefaultRadius(const EmbreeScene& scene, const Camera& camera);

class PpmRenderer : public SplatRenderer {
  public:
    // InvalidArgument naming "ppm" for alpha outside (0, 1) or a negative or non-finite
    // initial_radius. photons_per_pass 0 means width x height of the camera's image (pbrt-v4's
    // default); initial_radius 0 means PpmDefaultRadius.
    static absl::StatusOr<std::unique_ptr<PpmRenderer>> Create(const EmbreeScene& scene,
                                                               const Camera& camera,
                                                               const SplatRenderSettings& settings);

    // Passes [sample_begin, sample_end) for every pixel of work.rect (the path range, which the
    // plan makes equal, is not read). No splats.
    void Render(const SplatWork& work, TileSums& camera, SplatList& splats,
                const std::atomic<bool>* cancel = nullptr) const override;

    // Pass `pass`'s photon map (radius Radius(pass)); traced in parallel chunks whose photons
    // are concatenated in photon order. Its rays are added to stats.rays. A pass's photons and
    // camera rays share one time in the shutter, PassTime(pass), so that every photon a camera
    // vertex gathers was where that vertex is (motion blur); the passes spread it over the
    // shutter.
    PhotonMap TracePhotons(uint64_t pass, RenderStats& stats,
                           const std::atomic<bool>* cancel = nullptr) const;
    // Pass `pass`'s estimate along camera ray `ray` with `map` (TracePhotons(pass)).
    Rgb Li(const Ray& ray, const PhotonMap& map, Sampler& sampler, RenderStats& stats) const;

    double initial_radius() const { return initial_radius_; }
    uint64_t photons_per_pass() const { return photons_per_pass_; }
    float Radius(uint64_t pass) const;
    float PassTime(uint64_t pass) const;

  private:
    PpmRenderer(const EmbreeScene& scene, const Camera& camera,
                const SplatRenderSettings& settings);
    // Photons [begin, end) of pass `pass`, appended to `out`.
    void TraceRange(uint64_t pass, uint64_t begin, uint64_t end, std::vector<Photon>& out,
                    RenderStats& stats) const;

    // Direct light at a camera vertex (non-delta BSDF, outgoing direction wo_world, inside
    // `medium`), by multiple importance sampling of the lights and the BSDF sample `bs`; a
    // delta lobe's sample adds nothing here (the path follows it).
    Rgb DirectLight(const SurfaceHit& hit, const Shading& sh, const Vec3& wo_world,
                    const Bsdf& bsdf, const std::optional<BsdfSample>& bs, int medium, float u_pick,
                    const Vec2& u_light, RenderStats& stats) const;

    const EmbreeScene& scene_;
    const Camera& camera_;
    SplatRenderSettings settings_;
    EmissionSampler emission_;
    LightSampler lights_;
    double initial_radius_;
    uint64_t photons_per_pass_;
};

}  // namespace lf
