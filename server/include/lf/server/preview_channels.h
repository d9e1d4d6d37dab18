// What the dashboard's preview can show of a result image: its beauty (R,G,B), the two
// half-sample estimates (A, B) and the AOVs it holds (albedo, normal, depth, illuminance), each
// turned into an R,G,B image that EncodePng can tone-map, with the tone curve that suits it.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/image.h"
#include "lf/core/tone_map.h"

namespace lf {

// The views `image` has, in a fixed order: beauty, A, B, albedo, normal, depth, illuminance.
std::vector<std::string> PreviewChannels(const Image& image);

struct ChannelView {
    Image rgb;  // R, G, B only
    // Radiance rolls off (filmic); albedo, remapped normals and depth are in [0, 1] already.
    ToneCurve tone = ToneCurve::kFilmic;
};

// The R,G,B image of view `channel`: normals remapped from [-1, 1] to [0, 1], depth and
// illuminance as grey scaled by the image's largest finite value (near and dim are dark).
// InvalidArgument naming the channel and the ones the image has for one it lacks.
absl::StatusOr<ChannelView> ViewChannel(const Image& image, const std::string& channel);

}  // namespace lf
