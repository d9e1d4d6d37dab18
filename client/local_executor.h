// The in-process executor of local mode: the farm's planner (server/plan.h) cuts the render into
// tasks, TBB threads run them with lf::RenderTile as a worker would, and the farm's merger
// (server/merge.h) assembles the image. So `lightfarm render` and a farm render of the same job
// are the same code and the same bits.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/camera.h"
#include "lf/core/image.h"
#include "lf/kernels/radiance.h"

namespace lf {

struct RenderSettings {
    uint64_t spp = 16;
    uint64_t seed = 0;
    int threads = 0;  // 0: all cores
    int tile = 32;
    int passes = 1;  // sample passes per tile, as on the farm
};

// Adaptive sampling (local mode): each tile gets passes of samples until its estimated relative
// error (EstimatedRelativeError, the A/B halves) is at most target_error, it has max_spp
// samples, or the time limit has passed. A tile's result depends only on how many samples it
// got, and that only on its own samples, so without a time limit the image is deterministic.
struct AdaptiveSettings {
    double target_error = 0;  // relative; 0: none
    double time_limit = 0;    // seconds; 0: none. Every tile still gets its first pass.
    uint64_t max_spp = 1 << 16;
};

struct AdaptiveReport {
    double estimated_error = 0;  // of the whole image (EstimatedRelativeError)
    double worst_tile_error = 0;
    int tiles = 0;
    int tiles_above_target = 0;  // stopped by max_spp or the time limit
    bool timed_out = false;
    uint64_t min_spp = 0, max_spp = 0;
    struct Tile {
        PixelRect rect;
        uint64_t spp = 0;
        double error = 0;  // EstimatedRelativeError at the end
    };
    std::vector<Tile> per_tile;  // in plan order
};

struct RenderOutput {
    Image image;  // R,G,B, A.*, B.*, spp
    RenderStats stats;
    double seconds = 0;
    AdaptiveReport adaptive;  // RenderImageAdaptive only
};

// Called from worker threads with (tasks done, tasks in all); must be thread-safe.
using ProgressFn = std::function<void(size_t, size_t)>;

absl::StatusOr<RenderOutput> RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                                         const RenderSettings& settings,
                                         const ProgressFn& progress = {});

// settings.spp is the first pass of every tile (rounded up to even, so A and B are equal
// halves); settings.passes is ignored. Progress counts finished tiles.
absl::StatusOr<RenderOutput> RenderImageAdaptive(const Camera& camera,
                                                 const RadianceEstimator& estimator,
                                                 const RenderSettings& settings,
                                                 const AdaptiveSettings& adaptive,
                                                 const ProgressFn& progress = {});

}  // namespace lf
