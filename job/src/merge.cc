#include "lf/job/merge.h"

#include "absl/strings/str_cat.h"
#include "lf/core/aov.h"

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
    // Samples [begin, end) hold this many even ones (the A half); the rest are odd (B).
    const uint64_t even = (task.sample_end + 1) / 2 - (task.sample_begin + 1) / 2;
    const PixelMask active = task.active();
    const ExactSum zero;
    for (size_t i = 0; i < sums.pixels.size(); ++i) {
        const PixelSums& p = sums.pixels[i];
        const bool sampled = active.Has(i);
        const uint64_t expected = sampled ? n : 0;
        if (p.Count() != expected) {
            return absl::InvalidArgumentError(absl::StrCat("task ", task.index, ": pixel ", i,
                                                           " has ", p.Count(),
                                                           " samples, the task ", expected));
        }
        if (sampled && p.count[0] != even) {
            return absl::InvalidArgumentError(absl::StrCat("task ", task.index, ": pixel ", i,
                                                           " has ", p.count[0],
                                                           " even samples, the task ", even));
        }
        // A pixel the task does not sample must come back untouched (a converged pixel of a
        // noise-threshold pass keeps the sums it stopped with).
        bool untouched = sampled || i >= sums.aov_pixels.size() || sums.aov_pixels[i] == AovSums{};
        for (int h = 0; h < 2; ++h) {
            for (int c = 0; c < 3; ++c) untouched = untouched && (sampled || p.sum[h][c] == zero);
        }
        if (!untouched) {
            return absl::InvalidArgumentError(absl::StrCat(
                "task ", task.index, ": pixel ", i, " is not sampled by the task but has sums"));
        }
    }
    return absl::OkStatus();
}

Image EmptyRenderImage(int width, int height, uint32_t aovs) {
    Image image(width, height);
    for (const char* name : {"R", "G", "B", "A.R", "A.G", "A.B", "B.R", "B.G", "B.B", "spp"}) {
        image.Channel(name);
    }
    for (int c = 0; c < 3; ++c) {
        if (aovs & kAovAlbedo) image.Channel(kAovAlbedoChannels[c]);
        if (aovs & kAovNormal) image.Channel(kAovNormalChannels[c]);
    }
    if (aovs & kAovDepth) image.Channel(kAovDepthChannel);
    if (aovs & kAovIlluminance) image.Channel(kAovIlluminanceChannel);
    return image;
}

std::vector<PixelRect> TileRects(const std::vector<RenderTask>& tasks) {
    std::vector<PixelRect> rects;
    std::map<std::pair<int, int>, size_t> seen;  // by (y0, x0)
    for (const RenderTask& t : tasks) {
        if (seen.emplace(Key(t.rect), rects.size()).second) rects.push_back(t.rect);
    }
    return rects;
}

absl::StatusOr<TileSums> TileMerger::AddToTile(int tile, const TileSums& sums) {
    if (sums.aovs != store_->aovs()) {
        return absl::InvalidArgumentError(absl::StrCat("result with AOVs [", AovListName(sums.aovs),
                                                       "], the job's [",
                                                       AovListName(store_->aovs()), "]"));
    }
    absl::StatusOr<TileSums> merged = store_->Get(tile);
    if (!merged.ok()) return merged.status();
    *merged += sums;
    if (absl::Status s = store_->Put(tile, *merged); !s.ok()) return s;
    return merged;
}

RenderMerger::RenderMerger(int width, int height, std::vector<RenderTask> tasks, uint32_t aovs)
    : RenderMerger(width, height, tasks, *MakeMemoryTileStore(TileRects(tasks), aovs)) {}

RenderMerger::RenderMerger(int width, int height, std::vector<RenderTask> tasks,
                           std::shared_ptr<TileStore> store)
    : TileMerger(width, height, std::move(store)),
      tasks_(std::move(tasks)),
      done_(tasks_.size(), false) {
    std::map<std::pair<int, int>, int> tile_at;
    for (int t = 0; t < int(this->store()->tiles().size()); ++t) {
        tile_at[Key(this->store()->tiles()[size_t(t)])] = t;
    }
    for (const RenderTask& task : tasks_) tile_of_.push_back(tile_at.at(Key(task.rect)));
}

absl::StatusOr<std::unique_ptr<RenderMerger>> RenderMerger::Make(int width, int height,
                                                                 std::vector<RenderTask> tasks,
                                                                 const TileStoreFactory& make_store,
                                                                 uint32_t aovs) {
    absl::StatusOr<std::unique_ptr<TileStore>> store = make_store(TileRects(tasks), aovs);
    if (!store.ok()) return store.status();
    return std::unique_ptr<RenderMerger>(
        new RenderMerger(width, height, std::move(tasks), std::move(*store)));
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
    if (absl::StatusOr<TileSums> merged = AddToTile(tile_of_[size_t(task_index)], sums);
        !merged.ok()) {
        return merged.status();
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

}  // namespace lf
