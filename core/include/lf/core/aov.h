// Auxiliary images (AOVs) a render can add beside the radiance, for denoisers (OIDN, OptiX take
// albedo and normal) and compositors (depth): values of each camera ray's first hit, averaged
// over the pixel's samples like the radiance.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"

namespace lf {

// A set of AOVs as bits; 0 is none.
enum AovFlag : uint32_t {
    kAovAlbedo = 1,  // EXR channels albedo.R, albedo.G, albedo.B
    kAovNormal = 2,  // normal.X, normal.Y, normal.Z: world-space shading normal
    kAovDepth = 4,   // depth.Z: distance from the camera along the ray
};
inline constexpr uint32_t kAllAovs = kAovAlbedo | kAovNormal | kAovDepth;

// The EXR channels of each AOV, as lf::Image names them.
inline constexpr const char* kAovAlbedoChannels[3] = {"albedo.R", "albedo.G", "albedo.B"};
inline constexpr const char* kAovNormalChannels[3] = {"normal.X", "normal.Y", "normal.Z"};
inline constexpr const char* kAovDepthChannel = "depth.Z";

// `--aov` lists: comma-separated names (albedo, normal, depth) or "all"; "" is none.
// InvalidArgument naming an unknown name and the known ones.
absl::StatusOr<uint32_t> ParseAovList(std::string_view list);

// The names of `aovs` in a fixed order, comma-separated ("albedo,normal,depth"; "" for none).
std::string AovListName(uint32_t aovs);

}  // namespace lf
