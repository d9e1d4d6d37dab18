// Planning a path-traced render into tasks: tiles x sample passes. A task's result depends on
// nothing but its rectangle and sample range (see lf::RenderTile), so tasks may run anywhere, in
// any order, and their sums merge into the same bits as one local render.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/pixel_mask.h"
#include "lf/job/settings.h"

namespace lf {

// The largest tile side on the farm (checked at submission, not by PlanRender): an encoded
// 192x192 tile is 3.8 MB, under gRPC's 4 MiB message limit.
inline constexpr int kMaxFarmTile = 192;
// As `lightfarm render --spp`: exact sums stay far from overflow below this.
inline constexpr uint64_t kMaxSpp = uint64_t(1) << 24;

struct RenderPlanSettings {
    int width = 0, height = 0;
    uint64_t spp = defaults::kSpp;
    int tile = defaults::kTile;
    int passes = defaults::kPasses;  // sample passes per tile, 1..spp
};

// Radiosity settings of a job in plain values (lf::MakeRadiosityOptions turns them into the
// kernel's options): `render` and `submit` share them, and the farm carries them.
struct RadiositySettings {
    int64_t patches = defaults::kRadiosityPatches;
    double patch_size = 0;
    std::string solver = defaults::kRadiositySolver;
    double tolerance = defaults::kRadiosityTolerance;
    int max_iterations = defaults::kRadiosityMaxIterations;
    std::string display = defaults::kRadiosityDisplay;
    // On the farm, with solver "jacobi": patch-group tasks per sweep (lf/job/radiosity_solve.h).
    int sweep_tasks = defaults::kRadiositySweepTasks;
    // Most patches mesh refinement may reach (RadiosityOptions::max_patches); 0: 16 times the
    // coarse mesh's.
    int64_t max_patches = 0;
    // "flat" or "hierarchical" (RadiosityOptions::hierarchical); hierarchical solves by Jacobi
    // sweeps, refining links until each carries at most link_error of the scene's power.
    std::string form = defaults::kRadiosityForm;
    double link_error = defaults::kRadiosityLinkError;
};
inline constexpr int kMaxSweepTasks = 1024;
// A sweep's input (one RGB a side) up to this size goes with each lease of the sweep instead of
// through the blob store: no write, fsync and fetch a sweep (about 4 ms of the Cornell box's
// 18 ms sweeps on two workers); larger (above ~87k sides) it is a blob, fetched once a worker.
inline constexpr size_t kMaxInlineRadiosityBytes = size_t(1) << 20;
// The largest lease a worker takes (its gRPC receive limit): the job's spec, which came in a
// request of at most 4 MiB (the coordinator's kMaxRequestBytes), a sweep's input and the task's
// own fields, with room to spare.
inline constexpr size_t kMaxLeaseBytes = (size_t(6) << 20) + kMaxInlineRadiosityBytes;

struct RenderTask {
    int index = 0;  // position in the plan
    PixelRect rect;
    uint64_t sample_begin = 0, sample_end = 0;
    // A noise-threshold pass: the pixels still sampled (PixelMask::bits of rect); empty: all.
    std::string active_pixels;

    PixelMask active() const { return {rect, active_pixels}; }
    int64_t ActivePixels() const { return active().Count(); }
    // Pixel samples the task renders.
    uint64_t Samples() const { return uint64_t(ActivePixels()) * (sample_end - sample_begin); }
};

// Tile by tile, row by row, each tile's passes consecutive, so the tiles
// being merged at any moment are few. Pass p covers samples [spp*p/passes, spp*(p+1)/passes).
// InvalidArgument for sizes out of range (spp above kMaxSpp included).
absl::StatusOr<std::vector<RenderTask>> PlanRender(const RenderPlanSettings& settings);

}  // namespace lf
