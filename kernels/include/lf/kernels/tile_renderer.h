// Rendering a rectangle of the image over a range of samples: the unit of work of farm tasks
// and of local mode (lf/local/local_executor.h).
#pragma once

#include <atomic>
#include <cstdint>

#include "lf/core/camera.h"
#include "lf/core/film.h"
#include "lf/core/pixel_mask.h"
#include "lf/core/sampler.h"
#include "lf/kernels/radiance.h"

namespace lf {

// What every sample of a render does besides estimating radiance and where its random numbers
// come from. The defaults are the kernel's oldest behaviour (no clamp, no AOVs, independent
// numbers: a tile has the bits it had before these options existed); jobs and local renders
// pass their own, whose sampler defaults to defaults::kSampler (lf/job/settings.h).
struct SampleOptions {
    // Above 0: a sample whose radiance exceeds it in some channel is scaled so that its largest
    // channel equals it (Cycles' sample clamp: the hue stays, fireflies and their energy go).
    double clamp = 0;
    uint32_t aovs = 0;  // lf/core/aov.h flags: the first-hit AOVs to sum (aov_tracer.h)
    SamplerType sampler = SamplerType::kIndependent;
};

// Samples [sample_begin, sample_end) of every pixel of `rect`. Sample s of pixel (x, y) uses
// Sampler(seed, x, y, s, options.sampler); its first two numbers place it in the pixel through the
// camera's pixel filter (Camera::SampleFilm), and it adds to pixel (x, y) alone with weight 1, so
// the result depends on nothing else: not the tiling, not the thread. AOVs draw no random numbers.
// Its time in the shutter (motion blur: Ray::time) is Sampler::GetTime, which shifts no other
// number, so scenes where nothing moves render the same bits with a shutter as without.
// With `active`, only the pixels it has get samples (per-pixel adaptive sampling).
TileSums RenderTile(const Camera& camera, const RadianceEstimator& estimator, const PixelRect& rect,
                    uint64_t seed, uint64_t sample_begin, uint64_t sample_end,
                    const SampleOptions& options = {}, const std::atomic<bool>* cancel = nullptr,
                    const PixelMask* active = nullptr);

}  // namespace lf
