// Merging task results into an image. Results arrive in any order, from any worker; exact sums
// make the order irrelevant to the bits. Each tile's sums live in a TileStore (memory or a file),
// so a merge holds one tile in memory and the image exists only while a snapshot is made.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/job/plan.h"
#include "lf/job/tile_store.h"

namespace lf {

// InvalidArgument when `sums` is not `task`'s rectangle with its sample count in every pixel.
absl::Status CheckTaskResult(const RenderTask& task, const TileSums& sums);

// A black image with every channel lf::Image::SetTile writes for tiles with AOVs `aovs`, so that
// a snapshot of an unfinished render has them all.
Image EmptyRenderImage(int width, int height, uint32_t aovs = 0);

// The distinct rectangles of `tasks`, in the order they first appear.
std::vector<PixelRect> TileRects(const std::vector<RenderTask>& tasks);

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

    // R,G,B, A.*, B.* and spp of everything merged so far (RenderImageOf the store). Once
    // Complete(), bit for bit what local mode (lf/local/local_executor.h) makes of the same
    // settings.
    absl::StatusOr<Image> Snapshot() const { return RenderImageOf(*store_, width_, height_); }
    // The tiles' sums; shared so that a snapshot can be read from it without the merger (the
    // store is safe to read while the merger puts).
    std::shared_ptr<const TileStore> store() const { return store_; }
    int width() const { return width_; }
    int height() const { return height_; }

  protected:
    TileMerger(int width, int height, std::shared_ptr<TileStore> store)
        : width_(width), height_(height), store_(std::move(store)) {}
    // Adds `sums` to tile `tile`'s in the store; the tile's sums after, or the store's error (and
    // nothing added). InvalidArgument when `sums` carries other AOVs than the store.
    absl::StatusOr<TileSums> AddToTile(int tile, const TileSums& sums);

  private:
    int width_, height_;
    std::shared_ptr<TileStore> store_;
};

class RenderMerger : public TileMerger {
  public:
    // Keeps the tiles in memory; results carry the AOVs `aovs` (lf/core/aov.h flags).
    RenderMerger(int width, int height, std::vector<RenderTask> tasks, uint32_t aovs = 0);
    // Keeps the tiles where `make_store` says; its error when it cannot make the store.
    static absl::StatusOr<std::unique_ptr<RenderMerger>> Make(int width, int height,
                                                              std::vector<RenderTask> tasks,
                                                              const TileStoreFactory& make_store,
                                                              uint32_t aovs = 0);

    // Adds the result of task `task_index`. InvalidArgument when `sums` is not that task's
    // rectangle with that task's sample count in every pixel and the merger's AOVs; AlreadyExists
    // when the task was merged before (the image is unchanged then); the store's error when it
    // cannot read or write the tile (the task is then not merged).
    absl::Status Add(int task_index, const TileSums& sums);

    absl::StatusOr<std::vector<RenderTask>> Merge(int task_index, const TileSums& sums) override;

    const std::vector<RenderTask>& tasks() const override { return tasks_; }
    size_t tasks_done() const override { return tasks_done_; }
    size_t task_count() const { return tasks_.size(); }
    bool Complete() const override { return tasks_done_ == tasks_.size(); }
    const RenderStats& stats() const override { return stats_; }

  private:
    RenderMerger(int width, int height, std::vector<RenderTask> tasks,
                 std::shared_ptr<TileStore> store);

    std::vector<RenderTask> tasks_;
    std::vector<int> tile_of_;  // the store's tile of each task
    std::vector<bool> done_;
    size_t tasks_done_ = 0;
    RenderStats stats_;
};

}  // namespace lf
