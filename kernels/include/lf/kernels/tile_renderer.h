// Rendering rectangles of the image: the unit of work of local mode and of farm tasks.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/kernels/radiance.h"

namespace lf {

// Samples [sample_begin, sample_end) of every pixel of `rect`. Sample s of pixel (x, y) uses
// Sampler(seed, x, y, s) and its first two numbers place it in the pixel (box filter), so the
// result depends on nothing else: not the tiling, not the thread.
TileSums RenderTile(const Camera& camera, const RadianceEstimator& estimator, const PixelRect& rect,
                    uint64_t seed, uint64_t sample_begin, uint64_t sample_end,
                    const std::atomic<bool>* cancel = nullptr);

// Square tiles of side `tile` covering the image, row by row.
std::vector<PixelRect> PlanTiles(int width, int height, int tile);

struct RenderSettings {
    uint64_t spp = 16;
    uint64_t seed = 0;
    int threads = 0;  // 0: all cores
    int tile = 32;
};

struct RenderOutput {
    Image image;
    RenderStats stats;
    double seconds = 0;
};

// Called from worker threads with (tiles done, tiles in all); must be thread-safe.
using ProgressFn = std::function<void(size_t, size_t)>;

// Renders every tile in parallel (TBB) into R,G,B, A.*, B.* and spp channels.
RenderOutput RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                         const RenderSettings& settings, const ProgressFn& progress = {});

}  // namespace lf
