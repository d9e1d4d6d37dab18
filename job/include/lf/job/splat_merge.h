// Merging frame-pass task results (lf/job/splat_plan.h): each task's camera sums go into a tile
// store as tile results do (lf/job/merge.h), and its splat list is split by tile and added into a
// second store of the same tiles, so a job holds one tile in memory at a time, never a dense
// full-frame layer. All sums are exact: any order of tasks gives the same bits.
//
// Normalisation. A kernel splats, for each light path, its contribution with the camera's
// importance normalised over the whole film (as pbrt-v4's cameras do: We integrates to 1 over
// the film), i.e. as if the frame were one pixel. With N light paths over a frame of P = W x H
// pixels, a pixel's estimate is
//     camera sum / camera samples  +  splat sum x P / N,
// that is, the splat sum divided by the light paths per pixel-equivalent N / P (pbrt-v4 divides
// splats by spp, having traced spp light paths per pixel: the same). Each half (A, B) is
// normalised by its own light paths: half h's estimate is its camera mean plus its splat sum x
// P / N_h, N_h the merged light paths of parity h. A snapshot before the end divides by the
// light paths merged so far, so it is an unbiased image of fewer paths.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"
#include "lf/core/splat_list.h"
#include "lf/job/splat_plan.h"
#include "lf/job/tile_store.h"

namespace lf {

struct SplatNormalization {
    uint64_t frame_pixels = 0;        // W x H
    std::array<uint64_t, 2> paths{};  // light paths merged, by half

    // The factor of half `half`'s splat sum (0 to 1), or of both halves' sum (-1); 0 before any
    // light path.
    double Scale(int half) const;
};

// Writes R,G,B, A.*, B.* and spp of a tile from its camera sums and splat sums (same rect; the
// splat tile's counts are ignored), normalised as the file comment says: local mode and the
// coordinator both call this, so their images have the same bits. spp is the camera samples.
void SetSplatTile(Image& image, const TileSums& camera, const TileSums& splats,
                  const SplatNormalization& norm);

class SplatMerger {
  public:
    // Tiles of side `tile` in memory (the tile of the plan's settings).
    static absl::StatusOr<std::unique_ptr<SplatMerger>> Make(int width, int height, int tile,
                                                             SplatPlanKind kind,
                                                             std::vector<SplatTask> tasks);
    // Tiles where `make_store` says (two stores: camera sums, splat sums).
    static absl::StatusOr<std::unique_ptr<SplatMerger>> Make(int width, int height, int tile,
                                                             SplatPlanKind kind,
                                                             std::vector<SplatTask> tasks,
                                                             const TileStoreFactory& make_store);

    // Adds task `task_index`'s result: `camera` its camera tile (an empty rect when the task has
    // none), `splats` its splat list (coalesced here). InvalidArgument when the camera sums are
    // not the task's rectangle and sample count, the splats another frame's or (photon passes)
    // not empty; AlreadyExists when the task was merged before (the image is unchanged). The
    // store's error when it cannot read or write a tile: the tiles already added are remembered
    // (per task and tile), so adding the same result again completes the task without counting
    // any tile twice.
    absl::Status Add(int task_index, const TileSums& camera, SplatList& splats);

    const std::vector<SplatTask>& tasks() const { return tasks_; }
    size_t tasks_done() const { return tasks_done_; }
    bool Complete() const { return tasks_done_ == tasks_.size(); }
    const RenderStats& stats() const { return stats_; }
    const SplatNormalization& normalization() const { return norm_; }

    // The image of everything merged so far (SetSplatTile of every tile). Once Complete(), the
    // bits local mode makes of the same render.
    absl::StatusOr<Image> Snapshot() const;

    // What Snapshot reads, to be read after the caller's lock is released (the coordinator
    // takes previews without holding its scheduler while every tile is read): the stores,
    // shared, and the normalisation as it is now. Tiles merged after this call may show with
    // the older normalisation, a preview's blemish only: nothing merges once Complete(), so a
    // source taken then reads Snapshot's bits.
    struct SnapshotSource {
        int width = 0, height = 0;
        std::shared_ptr<const TileStore> camera, splats;
        SplatNormalization norm;
        absl::StatusOr<Image> Read() const;
    };
    SnapshotSource snapshot_source() const { return {width_, height_, camera_, splats_, norm_}; }

  private:
    SplatMerger(int width, int height, int tile, SplatPlanKind kind, std::vector<SplatTask> tasks,
                std::unique_ptr<TileStore> camera, std::unique_ptr<TileStore> splats);
    int TileOf(int x, int y) const { return (y / tile_) * columns_ + x / tile_; }
    // Adds `add` to tile `tile` of `store` unless task `task` did so before.
    absl::Status AddOnce(int task, TileStore& store, int tile, int slot,
                         const std::function<void(TileSums&)>& add);

    int width_, height_, tile_, columns_;
    SplatPlanKind kind_;
    std::vector<SplatTask> tasks_;
    std::shared_ptr<TileStore> camera_, splats_;  // shared with snapshot sources
    std::vector<bool> done_;
    // Tasks partly merged when a store failed: slots (splat tile t, camera tile T + t) added.
    std::map<int, std::vector<bool>> partial_;
    size_t tasks_done_ = 0;
    RenderStats stats_;
    SplatNormalization norm_;
};

}  // namespace lf
