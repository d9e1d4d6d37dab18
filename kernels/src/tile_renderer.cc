#include "lf/kernels/tile_renderer.h"

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
                const Vec2 lens = camera.HasLens() ? sampler.Get2D() : Vec2{};
                const Ray ray = camera.GenerateRay(x, y, film.x, film.y, lens);
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

}  // namespace lf
