// Image files for tests, made in memory: what a scene's textures are read from.
#pragma once

#include <stb_image_write.h>

#include <cstdint>
#include <string>
#include <vector>

namespace lf::testing {

// stb_image_write's callback: appends the encoded bytes to the std::string `context`.
inline void AppendToString(void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
}

// A PNG of `width` x `height` 8-bit texels with `channels` interleaved channels, top row first.
inline std::string PngBytes(int width, int height, int channels,
                            const std::vector<uint8_t>& texels) {
    std::string out;
    stbi_write_png_to_func(AppendToString, &out, width, height, channels, texels.data(),
                           width * channels);
    return out;
}

// A Radiance HDR (RGBE) image of `width` x `height` linear RGB texels, top row first. RGBE keeps
// 8 bits of mantissa per channel: powers of two (and 0) survive exactly.
inline std::string HdrBytes(int width, int height, const std::vector<float>& rgb) {
    std::string out;
    stbi_write_hdr_to_func(AppendToString, &out, width, height, 3, rgb.data());
    return out;
}

}  // namespace lf::testing
