// OpenEXR and PNG files. EXR keeps every channel as float32 plus header attributes saying how
// the image was made; PNG is an sRGB preview of R,G,B, clamped.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <variant>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/image.h"

namespace lf {

using ExrAttribute = std::variant<std::string, int, double>;
using ExrAttributes = std::map<std::string, ExrAttribute>;

struct ExrFile {
    Image image;
    ExrAttributes attributes;  // only the string, int and double ones
};

absl::Status WriteExr(const std::string& path, const Image& image, const ExrAttributes& attributes);
absl::StatusOr<ExrFile> ReadExr(const std::string& path);

// Linear [0, 1] to the sRGB transfer curve in 8 bits; clamped, NaN as 0.
uint8_t EncodeSrgb8(float linear);

// Linear to sRGB-encoded 8 bit, after scaling by 2^exposure.
absl::Status WritePng(const std::string& path, const Image& image, float exposure = 0.0f);

}  // namespace lf
