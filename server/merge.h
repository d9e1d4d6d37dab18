// Merging task results into an image. Results arrive in any order, from any worker; exact sums
// make the order irrelevant to the bits. Only tiles with some but not all passes merged hold
// sums; a finished tile is written into the image and its sums dropped.
#pragma once

#include <map>
#include <vector>

#include "absl/status/status.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "server/plan.h"

namespace lf {

class RenderMerger {
  public:
    RenderMerger(int width, int height, std::vector<RenderTask> tasks);

    // Adds the result of task `task_index`. InvalidArgument when `sums` is not that task's
    // rectangle with that task's sample count in every pixel; AlreadyExists when the task was
    // merged before (the image is unchanged then).
    absl::Status Add(int task_index, const TileSums& sums);

    size_t tasks_done() const { return tasks_done_; }
    size_t task_count() const { return tasks_.size(); }
    bool Complete() const { return tasks_done_ == tasks_.size(); }
    const RenderStats& stats() const { return stats_; }

    // R,G,B, A.*, B.* and spp of everything merged so far; once Complete(), the final image,
    // bit for bit what local mode (client/local_executor.h) makes of the same settings.
    Image Snapshot() const;

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
