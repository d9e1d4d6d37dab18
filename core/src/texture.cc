#include "lf/core/texture.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace lf {
namespace {

float SrgbToLinear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

// 8-bit texels decode through tables: a pow per channel per lookup would dominate shading.
struct DecodeTables {
    std::array<float, 256> srgb, linear;
    DecodeTables() {
        for (int i = 0; i < 256; ++i) {
            linear[size_t(i)] = float(i) / 255.0f;
            srgb[size_t(i)] = SrgbToLinear(linear[size_t(i)]);
        }
    }
};

const DecodeTables& Tables() {
    static const DecodeTables tables;
    return tables;
}

// An index in [0, n) from a texel coordinate, even where rounding of a huge one leaves it
// slightly outside.
int ClampIndex(double t, int n) { return int(std::clamp(t, 0.0, double(n - 1))); }

// The texel index a wrapped coordinate addresses. `t` is in texels and may be anything,
// including far outside the image or NaN (a degenerate uv): the result is always in [0, n).
int WrapIndex(double t, int n, TextureRef::Wrap wrap) {
    if (!std::isfinite(t)) return 0;
    switch (wrap) {
        case TextureRef::Wrap::kRepeat:
            return ClampIndex(t - n * std::floor(t / n), n);
        case TextureRef::Wrap::kMirroredRepeat: {
            const double period = 2.0 * n;
            const int m = int(std::clamp(t - period * std::floor(t / period), 0.0, period - 1));
            return m < n ? m : 2 * n - 1 - m;
        }
        case TextureRef::Wrap::kClampToEdge:
            break;
    }
    return ClampIndex(t, n);
}

}  // namespace

Rgba Texel(const TextureImage& image, int x, int y, bool srgb) {
    const size_t c = size_t(image.channels);
    const size_t at = (size_t(y) * size_t(image.width) + size_t(x)) * c;
    float v[4] = {0, 0, 0, 1};
    if (!image.texels8.empty()) {
        const std::array<float, 256>& table = srgb ? Tables().srgb : Tables().linear;
        const std::array<float, 256>& alpha = Tables().linear;
        for (size_t i = 0; i < c; ++i) {
            // Alpha is linear in every format: the second of grey-alpha, the fourth of RGBA.
            const bool is_alpha = (c == 2 && i == 1) || i == 3;
            v[i] = (is_alpha ? alpha : table)[image.texels8[at + i]];
        }
    } else {
        for (size_t i = 0; i < c; ++i) {
            const float t = image.texels32[at + i];
            const bool is_alpha = (c == 2 && i == 1) || i == 3;
            v[i] = srgb && !image.hdr && !is_alpha ? SrgbToLinear(t) : t;
        }
    }
    if (c <= 2) return {Rgb(v[0]), c == 2 ? v[1] : 1.0f};
    return {Rgb(v[0], v[1], v[2]), v[3]};
}

Vec2 TransformUv(const TextureRef& ref, const Vec2& uv) {
    if (ref.rotation == 0 && ref.scale.x == 1 && ref.scale.y == 1 && ref.offset.x == 0 &&
        ref.offset.y == 0) {
        return uv;
    }
    // KHR_texture_transform's translation * rotation * scale. Its worked example (offset [0, 1],
    // rotation pi/2, scale 0.5 selects the lower-left quadrant) fixes the rotation's sense in
    // uv with v pointing down.
    const float su = uv.x * ref.scale.x, sv = uv.y * ref.scale.y;
    const float c = std::cos(ref.rotation), s = std::sin(ref.rotation);
    return {c * su + s * sv + ref.offset.x, -s * su + c * sv + ref.offset.y};
}

Rgba Lookup(const TextureImage& image, const TextureRef& ref, const Vec2& uv_in) {
    const Vec2 uv = TransformUv(ref, uv_in);
    const int w = image.width, h = image.height;
    if (ref.nearest) {
        return Texel(image, WrapIndex(double(uv.x) * w, w, ref.wrap_s),
                     WrapIndex(double(uv.y) * h, h, ref.wrap_t), ref.srgb);
    }
    // Texel centres sit at half-integers: the four around the point, weighted by distance.
    const double x = double(uv.x) * w - 0.5, y = double(uv.y) * h - 0.5;
    const double x0 = std::isfinite(x) ? std::floor(x) : 0,
                 y0 = std::isfinite(y) ? std::floor(y) : 0;
    const float fx = float(std::isfinite(x) ? x - x0 : 0),
                fy = float(std::isfinite(y) ? y - y0 : 0);
    const int xa = WrapIndex(x0, w, ref.wrap_s), xb = WrapIndex(x0 + 1, w, ref.wrap_s);
    const int ya = WrapIndex(y0, h, ref.wrap_t), yb = WrapIndex(y0 + 1, h, ref.wrap_t);
    const Rgba t00 = Texel(image, xa, ya, ref.srgb), t10 = Texel(image, xb, ya, ref.srgb);
    const Rgba t01 = Texel(image, xa, yb, ref.srgb), t11 = Texel(image, xb, yb, ref.srgb);
    const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
    return {t00.rgb * w00 + t10.rgb * w10 + t01.rgb * w01 + t11.rgb * w11,
            t00.a * w00 + t10.a * w10 + t01.a * w01 + t11.a * w11};
}

}  // namespace lf
