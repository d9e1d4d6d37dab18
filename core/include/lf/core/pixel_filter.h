// Pixel filters (lf::PixelFilter in scene.h) by name, as the JSON camera's "filter" and the
// `--filter` flag spell them.
#pragma once

#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"

namespace lf {

// "box", "gaussian", "blackman-harris"
const char* PixelFilterTypeName(PixelFilter::Type type);
std::optional<PixelFilter::Type> PixelFilterTypeFromName(const std::string& name);

// Widths a filter may have: box exactly 1 (the seeds' pixel footprint), the others in
// [kMinFilterWidth, kMaxFilterWidth] pixels.
inline constexpr double kMinFilterWidth = 0.5, kMaxFilterWidth = 16;
// Ok, or InvalidArgument saying what is wrong with the width (without naming where: the caller
// knows whether it is a JSON path or a flag).
absl::Status CheckPixelFilter(const PixelFilter& filter);

// "gaussian 3 px" style text for logs and the EXR header ("box" for the box filter).
std::string DescribePixelFilter(const PixelFilter& filter);

}  // namespace lf
