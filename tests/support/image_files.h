// Image files for tests, made in memory: what a scene's textures are read from.
#pragma once

#include <stb_image_write.h>

#include <cstdint>
#include <string>
#include <vector>

namespace lf::testing {

// A PNG of `width` x `height` 8-bit texels with `channels` interleaved channels, top row first.
inline std::string PngBytes(int width, int height, int channels,
                            const std::vector<uint8_t>& texels) {
    std::string out;
    stbi_write_png_to_func(
        [](void* context, void* data, int size) {
            static_cast<std::string*>(context)->append(static_cast<const char*>(data),
                                                       size_t(size));
        },
        &out, width, height, channels, texels.data(), width * channels);
    return out;
}

}  // namespace lf::testing
