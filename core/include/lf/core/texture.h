// Texture lookup: a TextureRef's image at texture coordinates (u, v), after KHR_texture_transform
// and the wrap modes, filtered bilinearly (or nearest when the sampler asks), in linear values.
#pragma once

#include "lf/core/rgb.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"

namespace lf {

struct Rgba {
    Rgb rgb;
    float a = 1;
};

// An image's texel at integer (x, y) counted from its top-left corner, decoded: sRGB to linear
// for a colour ref, /255 for 8-bit data. Grey fills r, g and b; a missing alpha is 1.
Rgba Texel(const TextureImage& image, int x, int y, bool srgb);

// The filtered value of `ref`'s image at (u, v); (0, 0) is the top-left corner of the image and
// (1, 1) its bottom-right, texel centres at half-integers over the size.
Rgba Lookup(const TextureImage& image, const TextureRef& ref, const Vec2& uv);

// uv after `ref`'s KHR_texture_transform.
Vec2 TransformUv(const TextureRef& ref, const Vec2& uv);

}  // namespace lf
