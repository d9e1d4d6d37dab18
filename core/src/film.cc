#include "lf/core/film.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "lf/core/aov.h"

namespace lf {

namespace {
// Quantum 2^-50 (9e-16); a sample is clamped to 2^50 (1e15), so 2^26 samples at the clamp
// still fit in 127 bits. Radiance in any physical scene stays far inside both bounds.
constexpr int kFractionBits = 50;
constexpr double kLimit = 0x1p50;
}  // namespace

void ExactSum::Add(float x) {
    // Callers reject non-finite samples; clamping the magnitude keeps the conversion defined.
    const double v = std::clamp(double(x), -kLimit, kLimit);
    fixed_ += static_cast<__int128>(std::ldexp(v, kFractionBits));
}

double ExactSum::Value() const {
    // Two halves so the conversion rounds once, whatever the magnitude.
    const int64_t hi = int64_t(fixed_ >> 64);
    const uint64_t lo = uint64_t(static_cast<unsigned __int128>(fixed_));
    return std::ldexp(std::ldexp(double(hi), 64) + double(lo), -kFractionBits);
}

void PixelSums::Add(uint64_t sample_index, const Rgb& value) {
    const int half = int(sample_index & 1);
    for (int c = 0; c < 3; ++c) sum[half][c].Add(value[c]);
    ++count[half];
}

PixelSums& PixelSums::operator+=(const PixelSums& o) {
    for (int h = 0; h < 2; ++h) {
        for (int c = 0; c < 3; ++c) sum[h][c] += o.sum[h][c];
        count[h] += o.count[h];
    }
    return *this;
}

Rgb PixelSums::Mean() const {
    const uint32_t n = Count();
    if (n == 0) return Rgb(0);
    Rgb m;
    for (int c = 0; c < 3; ++c) {
        ExactSum s = sum[0][c];
        s += sum[1][c];
        m[c] = float(s.Value() / n);
    }
    return m;
}

Rgb PixelSums::HalfMean(int half) const {
    if (count[half] == 0) return Rgb(0);
    Rgb m;
    for (int c = 0; c < 3; ++c) m[c] = float(sum[half][c].Value() / count[half]);
    return m;
}

void AovSums::Add(uint32_t aovs, const FirstHit& hit) {
    if (aovs & kAovAlbedo) {
        for (int c = 0; c < 3; ++c) albedo[c].Add(hit.albedo[c]);
    }
    if (aovs & kAovNormal) {
        for (int c = 0; c < 3; ++c) normal[c].Add(hit.normal[c]);
    }
    if (aovs & kAovDepth) {
        depth.Add(hit.depth);
        ++depth_hits;
    }
    if (aovs & kAovIlluminance) illuminance.Add(hit.illuminance);
}

AovSums& AovSums::operator+=(const AovSums& o) {
    for (int c = 0; c < 3; ++c) {
        albedo[c] += o.albedo[c];
        normal[c] += o.normal[c];
    }
    depth += o.depth;
    illuminance += o.illuminance;
    depth_hits += o.depth_hits;
    return *this;
}

Rgb AovSums::Albedo(uint32_t samples) const {
    Rgb m(0);
    if (samples == 0) return m;
    for (int c = 0; c < 3; ++c) m[c] = float(albedo[c].Value() / samples);
    return m;
}

Vec3 AovSums::Normal(uint32_t samples) const {
    if (samples == 0) return {};
    return {float(normal[0].Value() / samples), float(normal[1].Value() / samples),
            float(normal[2].Value() / samples)};
}

float AovSums::Depth() const {
    if (depth_hits == 0) return std::numeric_limits<float>::infinity();
    return float(depth.Value() / depth_hits);
}

float AovSums::Illuminance(uint32_t samples) const {
    return samples == 0 ? 0.0f : float(illuminance.Value() / samples);
}

TileSums& TileSums::operator+=(const TileSums& o) {
    assert(o.rect == rect && o.aovs == aovs);
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] += o.pixels[i];
    for (size_t i = 0; i < aov_pixels.size(); ++i) aov_pixels[i] += o.aov_pixels[i];
    stats += o.stats;
    return *this;
}

}  // namespace lf
