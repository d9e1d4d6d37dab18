// Merging task results into an image. Results arrive in any order, from any worker; exact sums
// make the order irrelevant to the bits. Only tiles with some but not all passes merged hold
// sums; a finished tile is written into the image and its sums dropped.
#pragma once

#include <map>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/job/plan.h"

namespace lf {

// InvalidArgument when `sums` is not `task`'s rectangle with its sample count in every pixel.
absl::Status CheckTaskResult(const RenderTask& task, const TileSums& sums);

// A black image with every channel lf::Image::SetTile writes, so that a snapshot of an
// unfinished render has them all.
Image EmptyRenderImage(int width, int height);

// What a job's tile results merge into: a fixed plan (RenderMerger) or one that grows as results
// show which tiles need more samples (AdaptiveTilePlan, lf/job/adaptive_plan.h).
class TileMerger {
  public:
    virtual ~TileMerger() = default;
    // The tasks planned so far, by RenderTask::index.
    virtual const std::vector<RenderTask>& tasks() const = 0;
    // Merges task `task_index`'s result; returns the tasks it appended to the plan.
    virtual absl::StatusOr<std::vector<RenderTask>> Merge(int task_index, const TileSums& sums) = 0;
    virtual size_t tasks_done() const = 0;
    // Every planned task merged (or, adaptive, dropped) and none left to plan.
    virtual bool Complete() const = 0;
    virtual const RenderStats& stats() const = 0;
    // R,G,B, A.*, B.* and spp of everything merged so far.
    virtual Image Snapshot() const = 0;
};

class RenderMerger : public TileMerger {
  public:
    RenderMerger(int width, int height, std::vector<RenderTask> tasks);

    // Adds the result of task `task_index`. InvalidArgument when `sums` is not that task's
    // rectangle with that task's sample count in every pixel; AlreadyExists when the task was
    // merged before (the image is unchanged then).
    absl::Status Add(int task_index, const TileSums& sums);

    absl::StatusOr<std::vector<RenderTask>> Merge(int task_index, const TileSums& sums) override;

    const std::vector<RenderTask>& tasks() const override { return tasks_; }
    size_t tasks_done() const override { return tasks_done_; }
    size_t task_count() const { return tasks_.size(); }
    bool Complete() const override { return tasks_done_ == tasks_.size(); }
    const RenderStats& stats() const override { return stats_; }

    // Once Complete(), the final image, bit for bit what local mode (lf/local/local_executor.h)
    // makes of the same settings.
    Image Snapshot() const override;

  private:
    struct OpenTile {
        TileSums sums;
        int passes_left;
    };
    std::map<std::pair<int, int>, OpenTile>::iterator OpenTileFor(const RenderTask& task);

    std::vector<RenderTask> tasks_;
    std::vector<bool> done_;
    size_t tasks_done_ = 0;
    RenderStats stats_;
    Image image_;                                         // finished tiles
    std::map<std::pair<int, int>, int> passes_per_tile_;  // by (y0, x0)
    std::map<std::pair<int, int>, OpenTile> open_;
};

}  // namespace lf
