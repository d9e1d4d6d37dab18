// Where a merger keeps its tiles' exact sums between results: in memory (local mode), or in a
// file (the coordinator), so that a farm job's resident memory is the tile being merged, not its
// image. A store's tiles are fixed when it is made; Get and Put may be called from any thread.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"

namespace lf {

class TileStore {
  public:
    virtual ~TileStore() = default;
    const std::vector<PixelRect>& tiles() const { return tiles_; }
    // The AOVs (lf/core/aov.h flags) every tile's sums carry.
    uint32_t aovs() const { return aovs_; }

    // The sums last put for tile `tile`; zero sums of its rectangle before the first Put.
    virtual absl::StatusOr<TileSums> Get(int tile) const = 0;
    // Replaces tile `tile`'s sums. InvalidArgument, and nothing stored, when `sums` does not
    // cover exactly that tile or carries other AOVs than the store's.
    virtual absl::Status Put(int tile, const TileSums& sums) = 0;

  protected:
    TileStore(std::vector<PixelRect> tiles, uint32_t aovs)
        : tiles_(std::move(tiles)), aovs_(aovs) {}
    absl::Status CheckTile(int tile, const TileSums& sums) const;
    absl::Status CheckIndex(int tile) const;

  private:
    std::vector<PixelRect> tiles_;
    uint32_t aovs_;
};

// Makes the store of one merger, given its tiles and the AOVs their sums carry.
using TileStoreFactory = std::function<absl::StatusOr<std::unique_ptr<TileStore>>(
    std::vector<PixelRect> tiles, uint32_t aovs)>;

absl::StatusOr<std::unique_ptr<TileStore>> MakeMemoryTileStore(std::vector<PixelRect> tiles,
                                                               uint32_t aovs);

// A sparse file in `dir` holding every tile at a fixed offset (104 bytes a pixel, up to 116 more
// with AOVs), unlinked as soon as it is open: it goes when the store is destroyed or the process
// dies, and a restarted coordinator rebuilds it from the task results its job store recorded.
absl::StatusOr<std::unique_ptr<TileStore>> MakeFileTileStore(const std::string& dir,
                                                             std::vector<PixelRect> tiles,
                                                             uint32_t aovs);

// R,G,B, A.*, B.*, spp and the store's AOV channels of every tile's sums, reading one tile at a
// time (pixels outside every tile are black with spp 0).
absl::StatusOr<Image> RenderImageOf(const TileStore& store, int width, int height);

}  // namespace lf
