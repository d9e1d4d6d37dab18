#include "lf/kernels/tile_renderer.h"

#include "lf/core/aov.h"
#include "lf/core/photometry.h"
#include "lf/kernels/aov_tracer.h"

namespace lf {

namespace {

// The illuminance AOV's random numbers: the image's seed mixed with this, a stream apart from
// the radiance's.
constexpr uint64_t kIlluminanceStream = 0x2545f4914f6cdd1dULL;

// Lux at the first hit of `ray`: 0 where the estimate is not finite, as invalid samples add 0.
float FirstHitLux(const RadianceEstimator& estimator, const Ray& ray, Sampler& sampler,
                  RenderStats& stats) {
    const Rgb e = estimator.Irradiance(ray, sampler, stats).value_or(Rgb(0));
    return e.IsFinite() ? Photometric(e) : 0.0f;
}

}  // namespace

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
                    if (std::optional<FirstHit> hit = TraceFirstHit(estimator.geometry(), ray)) {
                        if (options.aovs & kAovIlluminance) {
                            Sampler aov_sampler(seed ^ kIlluminanceStream, x, y, s,
                                                options.sampler);
                            hit->illuminance = FirstHitLux(estimator, ray, aov_sampler, tile.stats);
                        }
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
