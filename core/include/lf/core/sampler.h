// Counter-based random numbers: every value is a pure function of (seed, pixel, sample index,
// dimension), so any split of the work into tiles, passes or threads gives the same bits.
#pragma once

#include <cstdint>

#include "lf/core/vec.h"

namespace lf {

// A 64-bit finaliser with full avalanche (Stafford's Mix13, as in SplitMix64).
constexpr uint64_t MixBits(uint64_t v) {
    v ^= v >> 30;
    v *= 0xbf58476d1ce4e5b9ULL;
    v ^= v >> 27;
    v *= 0x94d049bb133111ebULL;
    v ^= v >> 31;
    return v;
}

class Sampler {
  public:
    Sampler(uint64_t seed, int px, int py, uint64_t sample_index)
        : key_(MixBits(MixBits(seed ^ 0x9e3779b97f4a7c15ULL) ^
                       ((uint64_t(uint32_t(px)) << 32) | uint32_t(py))) ^
               MixBits(sample_index + 0x632be59bd9b4e019ULL)) {}

    // Uniform in [0, 1), 24 random bits so the float is exact and never rounds up to 1.
    float Get1D() { return float(Next() >> 40) * 0x1p-24f; }
    Vec2 Get2D() {
        const uint64_t bits = Next();
        return {float(bits >> 40) * 0x1p-24f, float((bits >> 8) & 0xffffff) * 0x1p-24f};
    }

  private:
    uint64_t Next() { return MixBits(key_ + (++dimension_) * 0x9e3779b97f4a7c15ULL); }

    uint64_t key_;
    uint64_t dimension_ = 0;
};

}  // namespace lf
