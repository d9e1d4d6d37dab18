// Rendering methods whose samples land anywhere on the image: light tracing ("light"),
// bidirectional path tracing ("bdpt") and progressive photon mapping ("ppm"). Their unit of work
// is a "splat pass" (lf/job/splat_plan.h plans them; lf/job/splat_merge.h merges them): a range
// of camera samples over a rectangle, and/or a range of light paths or photon passes over the
// whole frame. Its result is the rectangle's camera sums (TileSums) and a splat list
// (SplatList) of exact sums, so any split of a render over tasks, threads and machines adds up
// to the same bits.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "lf/core/camera.h"
#include "lf/core/film.h"
#include "lf/core/light_strategy.h"
#include "lf/core/sampler.h"
#include "lf/core/splat_list.h"

namespace lf {

// The settings of a splatting method; the job model's defaults (lf/job/settings.h) fill them.
struct SplatRenderSettings {
    int max_depth = 5;  // the most bounces of a path; negative: unlimited (roulette ends them)
    uint64_t seed = 0;
    SamplerType sampler = SamplerType::kSobol;
    // Above 0: each camera sample and each splat whose largest channel exceeds it is scaled down
    // to it, as the path tracer's clamp.
    double clamp = 0;
    // Next-event estimation of camera paths (bdpt's s = 1 strategy, ppm's direct light).
    LightStrategy light_strategy = LightStrategy::kBvh;
    // ppm: photons traced per pass; the radius of pass 0 (0: chosen from the scene's size and the
    // frame, see the method's docs); alpha of Knaus & Zwicker's schedule r_{i+1}^2 = r_i^2 (i +
    // alpha) / (i + 1), in (0, 1).
    uint64_t photons_per_pass = 0;
    double initial_radius = 0;
    double alpha = 2.0 / 3.0;
};

// One task's work (the kernel's view of lf::SplatTask; the job model is not a kernel
// dependency). Camera part: samples [sample_begin, sample_end) of every pixel of rect (none when
// rect is empty). Whole-frame part: light paths [path_begin, path_end) for "light"; for "ppm"
// the photon passes [path_begin, path_end), which equal the sample range; unused by "bdpt",
// whose light subpaths are those of its camera samples.
struct SplatWork {
    PixelRect rect;
    uint64_t sample_begin = 0, sample_end = 0;
    uint64_t path_begin = 0, path_end = 0;
};

class SplatRenderer {
  public:
    virtual ~SplatRenderer() = default;
    // Adds the work's camera samples into `camera` (whose rect is work.rect) and its light paths'
    // contributions into `splats` (a list of the camera's frame), and the rays cast and samples
    // taken into camera.stats. The result is a pure function of the work and the settings: any
    // split of a render gives the same sums. May run tbb::parallel_for inside (callers run it in
    // their task arena); stops early, leaving partial sums the caller discards, once `cancel`.
    virtual void Render(const SplatWork& work, TileSums& camera, SplatList& splats,
                        const std::atomic<bool>* cancel = nullptr) const = 0;
};

}  // namespace lf
