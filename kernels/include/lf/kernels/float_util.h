// Floating-point error analysis helpers (pbrt-v4, "Managing Rounding Error").
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace lf {

constexpr float kMachineEpsilon = std::numeric_limits<float>::epsilon() * 0.5f;

// Bound on the relative error of n chained float operations.
constexpr float Gamma(int n) { return (n * kMachineEpsilon) / (1 - n * kMachineEpsilon); }

inline float NextFloatUp(float v) {
    if (std::isinf(v) && v > 0) return v;
    if (v == -0.0f) v = 0.0f;
    uint32_t bits = std::bit_cast<uint32_t>(v);
    bits = v >= 0 ? bits + 1 : bits - 1;
    return std::bit_cast<float>(bits);
}

inline float NextFloatDown(float v) {
    if (std::isinf(v) && v < 0) return v;
    if (v == 0.0f) v = -0.0f;
    uint32_t bits = std::bit_cast<uint32_t>(v);
    bits = v > 0 ? bits - 1 : bits + 1;
    return std::bit_cast<float>(bits);
}

}  // namespace lf
