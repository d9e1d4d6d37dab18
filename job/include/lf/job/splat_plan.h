// Planning renders whose samples land anywhere on the image (light tracing, BDPT, photon
// mapping) into "splat pass" tasks. Tiles of camera samples (lf/job/plan.h) no longer suffice:
// a light path splats onto any pixel, and a photon pass needs a whole-frame photon map. A task
// is a range of light paths (or photon passes) over the whole frame, plus optionally a tile of
// camera samples; its result is the camera tile's sums (TileSums, possibly empty) and a splat
// list (lf/core/splat_list.h). Like tile tasks, a task's result depends on nothing but its
// ranges, so tasks may run anywhere, in any order, and merge into the same bits
// (lf/job/splat_merge.h).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/job/settings.h"

namespace lf {

enum class SplatPlanKind {
    // Light tracing (`light`): light paths [0, light_paths) over the whole frame, split into
    // consecutive ranges of at most max_paths_per_task; no camera part. Every light path splats.
    kLightPaths,
    // BDPT (`bdpt`): tiles x sample passes as PlanRender, each camera sample with its own light
    // subpath, whose t = 1 connections splat anywhere. The task's light paths are its camera
    // samples: tile area x samples of them.
    kCameraAndLight,
    // Photon passes (`ppm`, Knaus & Zwicker 2011): pass p traces its own photon map (a pure
    // function of p and the seed, so every tile of the pass rebuilds the same one) and gathers it
    // at camera sample p of each pixel of a tile. Tasks are tiles x ranges of at most
    // max_paths_per_task passes; no splats: the image is the average of the passes, per pixel.
    kPhotonPasses,
};

inline constexpr uint64_t kDefaultPathsPerTask = uint64_t(1) << 18;

struct SplatPlanSettings {
    int width = 0, height = 0;
    SplatPlanKind kind = SplatPlanKind::kLightPaths;
    // kLightPaths: light paths in all, at most kMaxSpp per pixel-equivalent (width x height).
    uint64_t light_paths = 0;
    // kLightPaths: light paths per task; kPhotonPasses: passes per task.
    uint64_t max_paths_per_task = kDefaultPathsPerTask;
    // kCameraAndLight: camera samples per pixel; kPhotonPasses: passes (one camera sample each).
    uint64_t spp = defaults::kSpp;
    // The tiles of the camera part, and the tiles the merger groups splats by.
    int tile = defaults::kTile;
    int passes = defaults::kPasses;  // kCameraAndLight: sample passes per tile, 1..spp
};

struct SplatTask {
    int index = 0;  // position in the plan
    // Camera part: samples [sample_begin, sample_end) of every pixel of rect; none when rect is
    // empty (kLightPaths).
    PixelRect rect;
    uint64_t sample_begin = 0, sample_end = 0;
    // Whole-frame part: light paths [path_begin, path_end) of the job (kLightPaths) or photon
    // passes [path_begin, path_end) (kPhotonPasses, equal to the sample range); 0, 0 for
    // kCameraAndLight, whose light paths are those of its camera samples. A kernel should draw
    // light path i's numbers as a pure function of i, so any split gives the same paths, with
    // half i & 1; e.g. Sampler(seed, q mod W, q / W, 2 (j / P) + (i & 1)) with j = i >> 1,
    // q = j mod P, P = W x H: each pixel-equivalent q then walks its own Sobol sequences, one
    // per half, in order, and the sampler's half is the splat's.
    uint64_t path_begin = 0, path_end = 0;
};

// kLightPaths: the ranges in order. kCameraAndLight: as PlanRender. kPhotonPasses: tile by tile,
// row by row, each tile's pass ranges consecutive. InvalidArgument for sizes out of range.
absl::StatusOr<std::vector<SplatTask>> PlanSplatRender(const SplatPlanSettings& settings);

// The light paths whose splats task `task` makes, by half (the parity of the light path's index
// for kLightPaths, of the camera sample's for kCameraAndLight); {0, 0} for kPhotonPasses. What
// the splats of merged tasks are divided by (lf::SplatNormalization).
std::array<uint64_t, 2> SplatPaths(SplatPlanKind kind, const SplatTask& task);

// The tile rectangles of a width x height frame in tiles of side `tile`, row by row: the camera
// rectangles of PlanSplatRender's tasks and the tiles splats are grouped by.
std::vector<PixelRect> SplatTiles(int width, int height, int tile);

}  // namespace lf
