// Sample accumulation. Sums are exact fixed point (quantum 2^-50) in 128-bit integers, so adding
// tiles, passes or threads in any order gives the same bits, and 10^6 samples in one pixel lose
// nothing to rounding.
#pragma once

#include <cstdint>
#include <vector>

#include "lf/core/rgb.h"
#include "lf/core/vec.h"

namespace lf {

class ExactSum {
  public:
    void Add(float x);
    ExactSum& operator+=(const ExactSum& o) {
        fixed_ += o.fixed_;
        return *this;
    }
    double Value() const;
    bool operator==(const ExactSum&) const = default;

    // The fixed-point integer itself, for encodings that must carry the sum exactly.
    static ExactSum FromFixed(__int128 fixed) {
        ExactSum s;
        s.fixed_ = fixed;
        return s;
    }
    __int128 fixed() const { return fixed_; }

  private:
    __int128 fixed_ = 0;
};

// Samples of one pixel split into two halves by sample index parity: the halves are two
// independent estimates whose difference measures the error of their mean.
struct PixelSums {
    ExactSum sum[2][3];
    uint32_t count[2] = {0, 0};

    void Add(uint64_t sample_index, const Rgb& value);
    PixelSums& operator+=(const PixelSums& o);
    uint32_t Count() const { return count[0] + count[1]; }
    Rgb Mean() const;
    Rgb HalfMean(int half) const;
};

// What a camera ray's first hit shows, for the AOVs (lf/core/aov.h).
struct FirstHit {
    Rgb albedo;       // the surface's reflectance there (lf/kernels/aov_tracer.h says which)
    Vec3 normal;      // world-space unit shading normal
    float depth = 0;  // distance from the ray's origin
    // Lux arriving on the side the ray sees (RadianceEstimator::Irradiance), when asked for.
    float illuminance = 0;
};

// The AOVs of one pixel's samples, summed exactly like the radiance. Albedo and normal are summed
// over the samples that hit (a miss adds 0) and averaged over all samples (PixelSums::Count);
// depth is summed and averaged over the `depth_hits` samples that hit only, +inf when none did;
// illuminance is summed and averaged like albedo (a miss reads 0 lux).
// Each value goes through ExactSum's clamp to +-2^50, so a depth (scene units reach 1e15) times
// kMaxSpp = 2^24 samples stays inside the 127 bits: 2^(50 + 50 + 24) = 2^124.
struct AovSums {
    ExactSum albedo[3], normal[3], depth, illuminance;
    uint32_t depth_hits = 0;

    // Adds only the AOVs `aovs` (flags) asks for, so unrequested sums stay zero.
    void Add(uint32_t aovs, const FirstHit& hit);
    AovSums& operator+=(const AovSums& o);
    bool operator==(const AovSums&) const = default;
    // Means over `samples` samples (PixelSums::Count()); 0 when there are none.
    Rgb Albedo(uint32_t samples) const;
    Vec3 Normal(uint32_t samples) const;
    float Depth() const;  // +inf when no sample hit
    float Illuminance(uint32_t samples) const;
};

struct PixelRect {
    int x0 = 0, y0 = 0, width = 0, height = 0;
    int64_t Area() const { return int64_t(width) * height; }
    bool operator==(const PixelRect&) const = default;
};

struct RenderStats {
    uint64_t samples = 0;
    uint64_t rays = 0;             // every ray cast, camera and shadow rays included
    uint64_t invalid_samples = 0;  // NaN or infinite samples, never written
    // Paths cut at the path tracer's hard depth cap (reflectance 1 keeps roulette from ending
    // them). Local mode only: the farm's tile encoding does not carry it.
    uint64_t truncated_paths = 0;
    RenderStats& operator+=(const RenderStats& o) {
        samples += o.samples;
        rays += o.rays;
        invalid_samples += o.invalid_samples;
        truncated_paths += o.truncated_paths;
        return *this;
    }
};

// The accumulated samples of one rectangle of the image.
struct TileSums {
    PixelRect rect;
    std::vector<PixelSums> pixels;  // row-major within rect
    RenderStats stats;
    uint32_t aovs = 0;                // lf/core/aov.h flags of the AOVs summed in aov_pixels
    std::vector<AovSums> aov_pixels;  // row-major like pixels; empty when aovs is 0

    explicit TileSums(const PixelRect& r, uint32_t aov_flags = 0)
        : rect(r), pixels(size_t(r.Area())), aovs(aov_flags) {
        if (aovs != 0) aov_pixels.resize(pixels.size());
    }
    size_t Index(int x, int y) const { return size_t(y - rect.y0) * rect.width + (x - rect.x0); }
    PixelSums& at(int x, int y) { return pixels[Index(x, y)]; }
    const PixelSums& at(int x, int y) const { return pixels[Index(x, y)]; }
    TileSums& operator+=(const TileSums& o);  // same rect and AOVs
};

}  // namespace lf
