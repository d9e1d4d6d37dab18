#include "lf/kernels/tile_renderer.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <mutex>

namespace lf {

TileSums RenderTile(const Camera& camera, const RadianceEstimator& estimator, const PixelRect& rect,
                    uint64_t seed, uint64_t sample_begin, uint64_t sample_end,
                    const std::atomic<bool>* cancel) {
    TileSums tile(rect);
    for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
        if (cancel && cancel->load(std::memory_order_relaxed)) break;
        for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
            PixelSums& pixel = tile.at(x, y);
            for (uint64_t s = sample_begin; s < sample_end; ++s) {
                Sampler sampler(seed, x, y, s);
                const Vec2 film = sampler.Get2D();
                const Ray ray = camera.GenerateRay(x, y, film.x, film.y);
                Rgb L = estimator.Li(ray, sampler, tile.stats);
                if (!L.IsFinite()) {
                    ++tile.stats.invalid_samples;
                    L = Rgb(0);
                }
                pixel.Add(s, L);
            }
        }
        tile.stats.samples += uint64_t(rect.width) * (sample_end - sample_begin);
    }
    return tile;
}

std::vector<PixelRect> PlanTiles(int width, int height, int tile) {
    std::vector<PixelRect> tiles;
    for (int y = 0; y < height; y += tile) {
        for (int x = 0; x < width; x += tile) {
            tiles.push_back({x, y, std::min(tile, width - x), std::min(tile, height - y)});
        }
    }
    return tiles;
}

RenderOutput RenderImage(const Camera& camera, const RadianceEstimator& estimator,
                         const RenderSettings& settings, const ProgressFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    RenderOutput out{Image(camera.width(), camera.height()), {}, 0};
    const std::vector<PixelRect> tiles = PlanTiles(camera.width(), camera.height(), settings.tile);
    std::mutex mutex;
    size_t done = 0;
    tbb::task_arena arena(settings.threads > 0 ? settings.threads
                                               : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, tiles.size(), 1),
            [&](const tbb::blocked_range<size_t>& range) {
                for (size_t i = range.begin(); i != range.end(); ++i) {
                    const TileSums tile = RenderTile(camera, estimator, tiles[i], settings.seed, 0,
                                                     settings.spp);
                    std::lock_guard<std::mutex> lock(mutex);
                    out.image.SetTile(tile);
                    out.stats += tile.stats;
                    ++done;
                    if (progress) progress(done, tiles.size());
                }
            },
            tbb::simple_partitioner());
    });
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace lf
