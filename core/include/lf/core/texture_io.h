// Image files to TextureImage: PNG, JPEG and Radiance HDR through stb_image, OpenEXR through
// OpenEXR. Each distinct file content is decoded once per process and shared: a texture used by
// many materials, scenes or jobs on one worker costs its memory once.
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"

namespace lf {

// The largest image side and texel count a scene may load: beyond them a "texture" is a mistake
// or an attack on the machine's memory, refused from the file's header before decoding.
inline constexpr int kMaxTextureSide = 32768;
inline constexpr int64_t kMaxTextureTexels = int64_t(1) << 28;

// Decodes `bytes`, the format found from their content (not the name). `name` names the image in
// errors and in TextureImage::name. InvalidArgument for a corrupt, unsupported or absurdly large
// image, naming it.
absl::StatusOr<std::shared_ptr<const TextureImage>> DecodeTexture(const std::string& bytes,
                                                                  const std::string& name);

}  // namespace lf
