// Linear RGB (Rec.709 primaries): the renderer's spectral representation.
#pragma once

#include <algorithm>
#include <cmath>

namespace lf {

struct Rgb {
    float r = 0, g = 0, b = 0;

    constexpr Rgb() = default;
    constexpr explicit Rgb(float v) : r(v), g(v), b(v) {}
    constexpr Rgb(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}

    constexpr float operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
    constexpr float& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }

    constexpr Rgb operator+(const Rgb& o) const { return {r + o.r, g + o.g, b + o.b}; }
    constexpr Rgb operator-(const Rgb& o) const { return {r - o.r, g - o.g, b - o.b}; }
    constexpr Rgb operator*(const Rgb& o) const { return {r * o.r, g * o.g, b * o.b}; }
    constexpr Rgb operator/(const Rgb& o) const { return {r / o.r, g / o.g, b / o.b}; }
    constexpr Rgb operator*(float s) const { return {r * s, g * s, b * s}; }
    constexpr Rgb operator/(float s) const { return {r / s, g / s, b / s}; }
    constexpr Rgb& operator+=(const Rgb& o) { return *this = *this + o; }
    constexpr Rgb& operator*=(const Rgb& o) { return *this = *this * o; }
    constexpr Rgb& operator*=(float s) { return *this = *this * s; }
    constexpr Rgb& operator/=(float s) { return *this = *this / s; }
    constexpr bool operator==(const Rgb&) const = default;

    constexpr bool IsBlack() const { return r == 0 && g == 0 && b == 0; }
    constexpr float MaxComponent() const { return std::max(r, std::max(g, b)); }
    constexpr float Average() const { return (r + g + b) / 3; }
    // Rec.709 luminance weights.
    constexpr float Luminance() const { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }
    bool IsFinite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
};

// An emitted colour with its NaN, infinite and negative channels as 0: HDR files can hold such
// texels, and they must emit nothing rather than poison an image or a normalisation.
inline Rgb EmittableRadiance(const Rgb& c) {
    const auto channel = [](float v) { return std::isfinite(v) && v > 0 ? v : 0.0f; };
    return {channel(c.r), channel(c.g), channel(c.b)};
}

constexpr Rgb operator*(float s, const Rgb& c) { return c * s; }

}  // namespace lf
