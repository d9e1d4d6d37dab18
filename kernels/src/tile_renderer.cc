#include "lf/kernels/tile_renderer.h"

#include "lf/kernels/aov_tracer.h"

namespace lf {

TileSums RenderTile(const Camera& camera, const RadianceEstimator& estimator, const PixelRect& rect,
                    uint64_t seed, uint64_t sample_begin, uint64_t sample_end,
                    const SampleOptions& options, const std::atomic<bool>* cancel,
                    const PixelMask* active) {
    TileSums tile(rect, options.aovs);
    for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
        if (cancel && cancel->load(std::memory_order_relaxed)) break;
        uint64_t pixels = 0;
        for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
            if (active && !active->Has(x, y)) continue;
            ++pixels;
            PixelSums& pixel = tile.at(x, y);
            for (uint64_t s = sample_begin; s < sample_end; ++s) {
                Sampler sampler(seed, x, y, s, options.sampler);
                const Vec2 film = camera.SampleFilm(sampler.Get2D());
                const Vec2 lens = camera.HasLens() ? sampler.Get2D() : Vec2{};
                const Ray ray = camera.GenerateRay(x, y, film.x, film.y, lens, sampler.GetTime());
                Rgb L = estimator.Li(ray, sampler, tile.stats);
                if (!L.IsFinite()) {
                    ++tile.stats.invalid_samples;
                    L = Rgb(0);
                }
                if (options.clamp > 0 && L.MaxComponent() > options.clamp) {
                    L *= float(options.clamp / L.MaxComponent());
                }
                pixel.Add(s, L);
                if (options.aovs != 0) {
                    ++tile.stats.rays;
                    if (const std::optional<FirstHit> hit =
                            TraceFirstHit(estimator.geometry(), ray)) {
                        tile.aov_pixels[tile.Index(x, y)].Add(options.aovs, *hit);
                    }
                }
            }
        }
        tile.stats.samples += pixels * (sample_end - sample_begin);
    }
    return tile;
}

}  // namespace lf
