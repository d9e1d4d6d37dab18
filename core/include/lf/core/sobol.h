// The first two dimensions of the Sobol sequence, a (0,2)-sequence in base 2: every aligned block
// of 2^m consecutive points is a (0,m,2)-net (each of the 2^m elementary intervals of area 2^-m
// holds exactly one point). With Owen scrambling done by hashing (Burley 2020, "Practical
// Hash-based Owen Scrambling", JCGT 9(4), after Laine and Karras 2011) the points are random
// yet keep that stratification, and a nested-uniform shuffle of the index gives every pixel and
// every pair of dimensions its own independent net (Burley's "shuffled scrambled Sobol").
#pragma once

#include <array>
#include <cstdint>

namespace lf {

constexpr uint32_t ReverseBits32(uint32_t v) {
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
    return (v >> 16) | (v << 16);
}

// A random permutation of 32-bit integers in which output bit j is input bit j flipped by a
// function of the bits below j only (addition carries and multiplications by even constants
// move information upwards only): Burley's improved Laine-Karras hash.
constexpr uint32_t LaineKarrasPermutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Owen's nested uniform scramble of a 32-bit fixed-point number in [0, 1): bit k (from the most
// significant) is flipped by a hash of the bits before it. Applied to an index it maps every
// aligned block of 2^m indices onto an aligned block of 2^m indices.
constexpr uint32_t NestedUniformScramble(uint32_t x, uint32_t seed) {
    return ReverseBits32(LaineKarrasPermutation(ReverseBits32(x), seed));
}

// Sobol dimension 0 (van der Corput): the index's bits mirrored about the binary point.
constexpr uint32_t SobolDimension0(uint32_t index) { return ReverseBits32(index); }

namespace sobol_internal {
// Dimension 1's generator matrix is Pascal's triangle mod 2: index bit k contributes column
// c_k, whose bit j (from the most significant) is binomial(k, j) mod 2; so c_0 = 1 << 31 and
// c_k = c_{k-1} ^ (c_{k-1} >> 1). Tabulated in the bit-reversed domain the scrambles work in
// (reversed index bit 31 - k contributes the reversed c_k) per index byte: four lookups.
constexpr std::array<std::array<uint32_t, 256>, 4> MakeReversedDimension1Tables() {
    std::array<uint32_t, 32> column{};
    column[0] = 1u << 31;
    for (int k = 1; k < 32; ++k) column[k] = column[k - 1] ^ (column[k - 1] >> 1);
    std::array<std::array<uint32_t, 256>, 4> tables{};
    for (int byte = 0; byte < 4; ++byte) {
        for (uint32_t value = 0; value < 256; ++value) {
            uint32_t x = 0;
            for (int bit = 0; bit < 8; ++bit) {
                if (value & (1u << bit)) x ^= ReverseBits32(column[31 - (8 * byte + bit)]);
            }
            tables[byte][value] = x;
        }
    }
    return tables;
}
inline constexpr std::array<std::array<uint32_t, 256>, 4> kReversedDimension1 =
    MakeReversedDimension1Tables();
}  // namespace sobol_internal

// ReverseBits32(SobolDimension1(ReverseBits32(reversed_index))): dimension 1 where index and
// point are both bit-reversed, as NestedUniformScramble's inner hash sees them; the sampler
// works there to save the reversals.
constexpr uint32_t ReversedSobolDimension1(uint32_t reversed_index) {
    const auto& t = sobol_internal::kReversedDimension1;
    return t[0][reversed_index & 0xff] ^ t[1][(reversed_index >> 8) & 0xff] ^
           t[2][(reversed_index >> 16) & 0xff] ^ t[3][reversed_index >> 24];
}

constexpr uint32_t SobolDimension1(uint32_t index) {
    return ReverseBits32(ReversedSobolDimension1(ReverseBits32(index)));
}

}  // namespace lf
