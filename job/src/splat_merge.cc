#include "lf/job/splat_merge.h"

#include <functional>

#include "absl/strings/str_cat.h"
#include "lf/job/merge.h"

namespace lf {

double SplatNormalization::Scale(int half) const {
    const uint64_t n = half < 0 ? paths[0] + paths[1] : paths[size_t(half)];
    return n == 0 ? 0.0 : double(frame_pixels) / double(n);
}

void SetSplatTile(Image& image, const TileSums& camera, const TileSums& splats,
                  const SplatNormalization& norm) {
    static const char* kRgb[3] = {"R", "G", "B"};
    std::vector<float>* mean[3];
    std::vector<float>* half[2][3];
    for (int c = 0; c < 3; ++c) {
        mean[c] = &image.Channel(kRgb[c]);
        half[0][c] = &image.Channel(std::string("A.") + kRgb[c]);
        half[1][c] = &image.Channel(std::string("B.") + kRgb[c]);
    }
    std::vector<float>& spp = image.Channel("spp");
    const double scale[3] = {norm.Scale(0), norm.Scale(1), norm.Scale(-1)};
    const PixelRect& r = camera.rect;
    for (int y = r.y0; y < r.y0 + r.height; ++y) {
        for (int x = r.x0; x < r.x0 + r.width; ++x) {
            const PixelSums& p = camera.at(x, y);
            const PixelSums& s = splats.at(x, y);
            const size_t i = size_t(y) * size_t(image.width()) + size_t(x);
            for (int c = 0; c < 3; ++c) {
                // In double from the exact sums, rounded to float once.
                double h[2];
                for (int k = 0; k < 2; ++k) {
                    h[k] = p.count[k] == 0 ? 0.0 : p.sum[k][c].Value() / p.count[k];
                    (*half[k][c])[i] = float(h[k] + s.sum[k][c].Value() * scale[k]);
                }
                ExactSum both = p.sum[0][c], splat = s.sum[0][c];
                both += p.sum[1][c];
                splat += s.sum[1][c];
                const double m = p.Count() == 0 ? 0.0 : both.Value() / p.Count();
                (*mean[c])[i] = float(m + splat.Value() * scale[2]);
            }
            spp[i] = float(p.Count());
        }
    }
}

absl::StatusOr<std::unique_ptr<SplatMerger>> SplatMerger::Make(int width, int height, int tile,
                                                               SplatPlanKind kind,
                                                               std::vector<SplatTask> tasks) {
    return Make(width, height, tile, kind, std::move(tasks), MakeMemoryTileStore);
}

absl::StatusOr<std::unique_ptr<SplatMerger>> SplatMerger::Make(int width, int height, int tile,
                                                               SplatPlanKind kind,
                                                               std::vector<SplatTask> tasks,
                                                               const TileStoreFactory& make_store) {
    if (width <= 0 || height <= 0 || tile < 1) {
        return absl::InvalidArgumentError(
            absl::StrCat("frame ", width, "x", height, " in tiles of ", tile, ": empty"));
    }
    const std::vector<PixelRect> tiles = SplatTiles(width, height, tile);
    for (const SplatTask& t : tasks) {
        // Camera parts must be tiles of the grid, so a task adds into exactly one store tile.
        if (t.rect.Area() == 0) continue;
        const bool on_grid =
            t.rect.x0 % tile == 0 && t.rect.y0 % tile == 0 && t.rect.x0 < width &&
            t.rect.y0 < height &&
            t.rect ==
                tiles[size_t((t.rect.y0 / tile) * ((width + tile - 1) / tile) + t.rect.x0 / tile)];
        if (!on_grid) {
            return absl::InvalidArgumentError(
                absl::StrCat("task ", t.index, ": camera rectangle ", t.rect.x0, ",", t.rect.y0,
                             " ", t.rect.width, "x", t.rect.height, " is not a tile of side ", tile,
                             " of the ", width, "x", height, " frame"));
        }
    }
    absl::StatusOr<std::unique_ptr<TileStore>> camera = make_store(tiles, 0);
    if (!camera.ok()) return camera.status();
    absl::StatusOr<std::unique_ptr<TileStore>> splats = make_store(tiles, 0);
    if (!splats.ok()) return splats.status();
    return std::unique_ptr<SplatMerger>(new SplatMerger(width, height, tile, kind, std::move(tasks),
                                                        std::move(*camera), std::move(*splats)));
}

SplatMerger::SplatMerger(int width, int height, int tile, SplatPlanKind kind,
                         std::vector<SplatTask> tasks, std::unique_ptr<TileStore> camera,
                         std::unique_ptr<TileStore> splats)
    : width_(width),
      height_(height),
      tile_(tile),
      columns_((width + tile - 1) / tile),
      kind_(kind),
      tasks_(std::move(tasks)),
      camera_(std::move(camera)),
      splats_(std::move(splats)),
      done_(tasks_.size(), false) {
    norm_.frame_pixels = uint64_t(width) * uint64_t(height);
}

absl::Status SplatMerger::AddOnce(int task, TileStore& store, int tile, int slot,
                                  const std::function<void(TileSums&)>& add) {
    std::vector<bool>& added = partial_[task];
    if (added.empty()) added.resize(2 * camera_->tiles().size(), false);
    if (added[size_t(slot)]) return absl::OkStatus();
    absl::StatusOr<TileSums> sums = store.Get(tile);
    if (!sums.ok()) return sums.status();
    add(*sums);
    if (absl::Status s = store.Put(tile, *sums); !s.ok()) return s;
    added[size_t(slot)] = true;
    return absl::OkStatus();
}

absl::Status SplatMerger::Add(int task_index, const TileSums& camera, SplatList& splats) {
    if (task_index < 0 || size_t(task_index) >= tasks_.size()) {
        return absl::InvalidArgumentError(absl::StrCat("no task ", task_index, " in the plan"));
    }
    if (done_[size_t(task_index)]) {
        return absl::AlreadyExistsError(absl::StrCat("task ", task_index, " is already merged"));
    }
    const SplatTask& task = tasks_[size_t(task_index)];
    // Everything is checked before the first tile is touched.
    if (task.rect.Area() == 0) {
        if (camera.rect.Area() != 0) {
            return absl::InvalidArgumentError(
                absl::StrCat("task ", task_index, ": has no camera part, the result a ",
                             camera.rect.width, "x", camera.rect.height, " tile"));
        }
    } else {
        const RenderTask as_tile{task.index, task.rect, task.sample_begin, task.sample_end};
        if (absl::Status s = CheckTaskResult(as_tile, camera); !s.ok()) return s;
        if (camera.aovs != 0) {
            return absl::InvalidArgumentError(
                absl::StrCat("task ", task_index, ": camera sums with AOVs, which splat passes ",
                             "do not carry"));
        }
    }
    if (splats.width() != width_ || splats.height() != height_) {
        return absl::InvalidArgumentError(absl::StrCat("task ", task_index, ": splats of a ",
                                                       splats.width(), "x", splats.height(),
                                                       " frame, the job's ", width_, "x", height_));
    }
    const std::vector<SplatEntry>& entries = splats.entries();
    if (kind_ == SplatPlanKind::kPhotonPasses && !entries.empty()) {
        return absl::InvalidArgumentError(
            absl::StrCat("task ", task_index, ": ", entries.size(),
                         " splats from a photon pass, which has none"));
    }

    const int tile_count = int(camera_->tiles().size());
    if (task.rect.Area() != 0) {
        const int t = TileOf(task.rect.x0, task.rect.y0);
        if (absl::Status s = AddOnce(task_index, *camera_, t, tile_count + t,
                                     [&](TileSums& sums) { sums += camera; });
            !s.ok()) {
            return s;
        }
    }
    // Group by tile: the tiles touched, in order, each adding its part of the list.
    std::vector<bool> touched(size_t(tile_count), false);
    for (const SplatEntry& e : entries) {
        touched[size_t(TileOf(int(e.pixel % uint32_t(width_)), int(e.pixel / uint32_t(width_))))] =
            true;
    }
    for (int t = 0; t < tile_count; ++t) {
        if (!touched[size_t(t)]) continue;
        const SplatList part = splats.Restrict(splats_->tiles()[size_t(t)]);
        if (absl::Status s =
                AddOnce(task_index, *splats_, t, t, [&](TileSums& sums) { part.AddTo(sums); });
            !s.ok()) {
            return s;
        }
    }
    partial_.erase(task_index);
    done_[size_t(task_index)] = true;
    ++tasks_done_;
    stats_ += camera.stats;
    const std::array<uint64_t, 2> paths = SplatPaths(kind_, task);
    norm_.paths[0] += paths[0];
    norm_.paths[1] += paths[1];
    return absl::OkStatus();
}

absl::StatusOr<Image> SplatMerger::Snapshot() const { return snapshot_source().Read(); }

absl::StatusOr<Image> SplatMerger::SnapshotSource::Read() const {
    Image image = EmptyRenderImage(width, height);
    for (int t = 0; t < int(camera->tiles().size()); ++t) {
        absl::StatusOr<TileSums> camera_sums = camera->Get(t);
        if (!camera_sums.ok()) return camera_sums.status();
        absl::StatusOr<TileSums> splat_sums = splats->Get(t);
        if (!splat_sums.ok()) return splat_sums.status();
        SetSplatTile(image, *camera_sums, *splat_sums, norm);
    }
    return image;
}

}  // namespace lf
