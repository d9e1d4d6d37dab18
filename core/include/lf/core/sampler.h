// Counter-based sample values: every value is a pure function of (seed, pixel, sample index,
// dimension), so any split of the work into tiles, passes or threads gives the same bits, and
// samples [a, b) of a pixel continue its samples [0, a).
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "lf/core/sobol.h"
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

// How a pixel's samples are spread over the unit hypercube:
//  - kIndependent: hashed independent uniform values; error falls as spp^-1/2.
//  - kSobol: each of a sample's first Sampler::kSobolDraws Get1D/Get2D draws is its own
//    shuffled, Owen-scrambled Sobol (0,2)-sequence (lf/core/sobol.h), independent across
//    pixels and dimensions, so every 2D projection of the camera and the first bounces is
//    stratified and smooth integrands converge faster than spp^-1/2; later draws are hashed
//    independent numbers.
//    Even and odd samples are two independent such sequences (sample s is point s/2 of
//    sequence s%2): the image's A and B halves (lf::PixelSums) are then independent
//    randomised-QMC estimates, and their difference stays an honest error estimate, which it
//    would not be if the halves were two correlated parts of one net.
enum class SamplerType { kIndependent, kSobol };

// The names of `--sampler`, the job record and the EXR header (lightfarm.sampler).
constexpr const char* SamplerTypeName(SamplerType type) {
    return type == SamplerType::kSobol ? "sobol" : "independent";
}
constexpr std::optional<SamplerType> SamplerTypeFromName(std::string_view name) {
    if (name == "sobol") return SamplerType::kSobol;
    if (name == "independent") return SamplerType::kIndependent;
    return std::nullopt;
}

class Sampler {
  public:
    // Sobol draws past this many are hashed independent numbers, as kIndependent's: the camera's
    // film draw and two bounces' (four draws each, PathTracer::Li) stay stratified (a lens
    // takes one of them).
    // Later bounces carry little of the image and their integrands are high-dimensional, so
    // stratifying them bought nothing measurable (Cornell box 128², 64 spp: RMSE 0.01227 cut
    // here against 0.01222 uncut, 0.01258 cut after one bounce) while each Sobol draw costs
    // about 17 ns against 2.5.
    static constexpr uint64_t kSobolDraws = 9;

    // Independent: every draw hashes the sample's key. Sobol: one key per pixel and half, the
    // same for all its samples, so that each draw's hash seeds one scrambled sequence they all
    // share; draws past kSobolDraws hash the sample's key as independent ones do.
    Sampler(uint64_t seed, int px, int py, uint64_t sample_index,
            SamplerType type = SamplerType::kIndependent)
        : sample_key_(PixelKey(seed, px, py) ^ MixBits(sample_index + 0x632be59bd9b4e019ULL)),
          sobol_key_(type == SamplerType::kSobol
                         ? MixBits(PixelKey(seed, px, py) ^ (sample_index & 1))
                         : 0),
          reversed_sobol_index_(
              type == SamplerType::kSobol ? ReverseBits32(uint32_t(sample_index >> 1)) : 0),
          sobol_draws_(type == SamplerType::kSobol ? kSobolDraws : 0) {}

    // Uniform in [0, 1), 24 bits so the float is exact and never rounds up to 1.
    float Get1D() {
        if (++dimension_ <= sobol_draws_) {
            const uint64_t h = Hash(sobol_key_);
            return ToFloat(ScrambledDimension0(ShuffledReversedIndex(h), h));
        }
        return float(Hash(sample_key_) >> 40) * 0x1p-24f;
    }
    Vec2 Get2D() {
        if (++dimension_ <= sobol_draws_) {
            const uint64_t h = Hash(sobol_key_);
            const uint32_t reversed = ShuffledReversedIndex(h);
            // NestedUniformScramble(SobolDimension1(index), seed), index = ReverseBits32(reversed)
            const uint32_t y = ReverseBits32(
                LaineKarrasPermutation(ReversedSobolDimension1(reversed), uint32_t(MixBits(h))));
            return {ToFloat(ScrambledDimension0(reversed, h)), ToFloat(y)};
        }
        const uint64_t bits = Hash(sample_key_);
        return {float(bits >> 40) * 0x1p-24f, float((bits >> 8) & 0xffffff) * 0x1p-24f};
    }

    // The sample's time in the shutter, uniform in [0, 1): a dimension of its own, outside the
    // sequence of Get1D/Get2D draws, so a render that takes it draws every other number as
    // one that does not (a static scene keeps its bits with a shutter). Stratified over the
    // pixel's samples like every other dimension (Sobol).
    float GetTime() const {
        if (sobol_draws_ > 0) {
            const uint64_t h = MixBits(sobol_key_ ^ kTimeKey);
            return ToFloat(ScrambledDimension0(ShuffledReversedIndex(h), h));
        }
        return float(MixBits(sample_key_ ^ kTimeKey) >> 40) * 0x1p-24f;
    }

  private:
    static constexpr uint64_t kTimeKey = 0x5851f42d4c957f2dULL;
    static constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ULL;

    static uint64_t PixelKey(uint64_t seed, int px, int py) {
        return MixBits(MixBits(seed ^ kGolden) ^ ((uint64_t(uint32_t(px)) << 32) | uint32_t(py)));
    }

    // The current draw's hash of a key: its random bits (independent) or its scrambles' seeds
    // (Sobol).
    uint64_t Hash(uint64_t key) const { return MixBits(key + dimension_ * kGolden); }
    static float ToFloat(uint32_t fixed) { return float(fixed >> 8) * 0x1p-24f; }
    // The draw's shuffled index, NestedUniformScramble(index in the half, seed), reversed: the
    // scramble reverses, hashes and reverses back, and the reversal is kept for the next step.
    uint32_t ShuffledReversedIndex(uint64_t h) const {
        return LaineKarrasPermutation(reversed_sobol_index_, uint32_t(h));
    }
    // NestedUniformScramble(SobolDimension0(index), seed): dimension 0 is the reversed index,
    // so the scramble's inner reversal gives the index itself.
    static uint32_t ScrambledDimension0(uint32_t reversed_index, uint64_t h) {
        return ReverseBits32(
            LaineKarrasPermutation(ReverseBits32(reversed_index), uint32_t(h >> 32)));
    }

    uint64_t sample_key_;
    uint64_t sobol_key_;
    uint32_t reversed_sobol_index_;  // the sample's index within its half, bit-reversed
    uint64_t sobol_draws_;           // kSobolDraws for Sobol, 0 for independent
    uint64_t dimension_ = 0;         // draws so far
};

}  // namespace lf
