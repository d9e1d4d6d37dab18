#include "lf/job/merge.h"

#include "absl/strings/str_cat.h"

namespace lf {

namespace {
std::pair<int, int> Key(const PixelRect& r) { return {r.y0, r.x0}; }
}  // namespace

absl::Status CheckTaskResult(const RenderTask& task, const TileSums& sums) {
    if (!(sums.rect == task.rect) || sums.pixels.size() != size_t(task.rect.Area())) {
        return absl::InvalidArgumentError(
            absl::StrCat("task ", task.index, ": result covers ", sums.rect.x0, ",", sums.rect.y0,
                         " ", sums.rect.width, "x", sums.rect.height, ", the task ", task.rect.x0,
                         ",", task.rect.y0, " ", task.rect.width, "x", task.rect.height));
    }
    const uint64_t n = task.sample_end - task.sample_begin;
    for (const PixelSums& p : sums.pixels) {
        if (p.Count() != n) {
            return absl::InvalidArgumentError(absl::StrCat("task ", task.index, ": a pixel has ",
                                                           p.Count(), " samples, the task ", n));
        }
    }
    return absl::OkStatus();
}

Image EmptyRenderImage(int width, int height) {
    Image image(width, height);
    for (const char* name : {"R", "G", "B", "A.R", "A.G", "A.B", "B.R", "B.G", "B.B", "spp"}) {
        image.Channel(name);
    }
    return image;
}

RenderMerger::RenderMerger(int width, int height, std::vector<RenderTask> tasks)
    : tasks_(std::move(tasks)),
      done_(tasks_.size(), false),
      image_(EmptyRenderImage(width, height)) {
    for (const RenderTask& t : tasks_) ++passes_per_tile_[Key(t.rect)];
}

absl::Status RenderMerger::Add(int task_index, const TileSums& sums) {
    if (task_index < 0 || size_t(task_index) >= tasks_.size()) {
        return absl::InvalidArgumentError(absl::StrCat("no task ", task_index, " in the plan"));
    }
    const RenderTask& task = tasks_[size_t(task_index)];
    if (done_[size_t(task_index)]) {
        return absl::AlreadyExistsError(absl::StrCat("task ", task_index, " is already merged"));
    }
    if (absl::Status s = CheckTaskResult(task, sums); !s.ok()) return s;
    auto open = OpenTileFor(task);
    open->second.sums += sums;
    if (--open->second.passes_left == 0) {
        image_.SetTile(open->second.sums);
        open_.erase(open);
    }
    done_[size_t(task_index)] = true;
    ++tasks_done_;
    stats_ += sums.stats;
    return absl::OkStatus();
}

absl::StatusOr<std::vector<RenderTask>> RenderMerger::Merge(int task_index, const TileSums& sums) {
    if (absl::Status s = Add(task_index, sums); !s.ok()) return s;
    return std::vector<RenderTask>();
}

std::map<std::pair<int, int>, RenderMerger::OpenTile>::iterator RenderMerger::OpenTileFor(
    const RenderTask& task) {
    auto it = open_.find(Key(task.rect));
    if (it != open_.end()) return it;
    return open_
        .emplace(Key(task.rect), OpenTile{TileSums(task.rect), passes_per_tile_[Key(task.rect)]})
        .first;
}

Image RenderMerger::Snapshot() const {
    Image image = image_;
    for (const auto& [key, tile] : open_) image.SetTile(tile.sums);
    return image;
}

}  // namespace lf
