// How next-event estimation chooses a light and a point on it. A job setting (`--light-sampling`,
// the job record, the wire, lightfarm.light_sampling in the EXR header), so it lives in core
// where the job model can name it; lf/kernels/lights.h implements both.
#pragma once

#include <optional>
#include <string_view>

namespace lf {

// - kPower: a light with probability proportional to its power, a point on it by area.
// - kBvh: a light by its importance at the shading point (a light BVH), a point on a triangle
//   or sphere by the solid angle it subtends where that is worth it (docs/rendering.md).
enum class LightStrategy { kPower, kBvh };

constexpr const char* LightStrategyName(LightStrategy strategy) {
    return strategy == LightStrategy::kBvh ? "bvh" : "power";
}
constexpr std::optional<LightStrategy> LightStrategyFromName(std::string_view name) {
    if (name == "bvh") return LightStrategy::kBvh;
    if (name == "power") return LightStrategy::kPower;
    return std::nullopt;
}

}  // namespace lf
