// Rendering a rectangle of the image over a range of samples: the unit of work of farm tasks
// and of local mode (lf/local/local_executor.h).
#pragma once

#include <atomic>
#include <cstdint>

#include "lf/core/camera.h"
#include "lf/core/film.h"
#include "lf/kernels/radiance.h"

namespace lf {

// Samples [sample_begin, sample_end) of every pixel of `rect`. Sample s of pixel (x, y) uses
// Sampler(seed, x, y, s) and its first two numbers place it in the pixel (box filter), so the
// result depends on nothing else: not the tiling, not the thread.
TileSums RenderTile(const Camera& camera, const RadianceEstimator& estimator, const PixelRect& rect,
                    uint64_t seed, uint64_t sample_begin, uint64_t sample_end,
                    const std::atomic<bool>* cancel = nullptr);

}  // namespace lf
