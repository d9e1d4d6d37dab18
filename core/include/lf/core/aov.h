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
    // illuminance: lux (683 lm/W x the Rec.709 luminance of the irradiance, W m^-2) arriving on
    // the side of the first hit the camera sees; 0 for a miss. Methods estimate it their own way
    // (RadianceEstimator::Irradiance) and some refuse it.
    kAovIlluminance = 8,
};
// What `all` asks for: the first-hit AOVs every method gives for one extra ray a sample.
// Illuminance is left out: it costs a radiance estimate a sample and not every method has it.
inline constexpr uint32_t kAllAovs = kAovAlbedo | kAovNormal | kAovDepth;
// Every flag a render may carry.
inline constexpr uint32_t kKnownAovs = kAllAovs | kAovIlluminance;

// The EXR channels of each AOV, as lf::Image names them.
inline constexpr const char* kAovAlbedoChannels[3] = {"albedo.R", "albedo.G", "albedo.B"};
inline constexpr const char* kAovNormalChannels[3] = {"normal.X", "normal.Y", "normal.Z"};
inline constexpr const char* kAovDepthChannel = "depth.Z";
inline constexpr const char* kAovIlluminanceChannel = "illuminance";

// `--aov` lists: comma-separated names (albedo, normal, depth, illuminance) or "all" (albedo,
// normal, depth); "" is none.
// InvalidArgument naming an unknown name and the known ones.
absl::StatusOr<uint32_t> ParseAovList(std::string_view list);

// The names of `aovs` in a fixed order, comma-separated ("albedo,normal,depth,illuminance"; ""
// for none).
std::string AovListName(uint32_t aovs);

}  // namespace lf
