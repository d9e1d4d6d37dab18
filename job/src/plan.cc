#include "lf/job/plan.h"

#include <algorithm>

#include "absl/strings/str_cat.h"

namespace lf {

absl::StatusOr<std::vector<RenderTask>> PlanRender(const RenderPlanSettings& s) {
    if (s.width <= 0 || s.height <= 0) {
        return absl::InvalidArgumentError(
            absl::StrCat("image size ", s.width, "x", s.height, " is empty"));
    }
    if (s.spp < 1 || s.spp > kMaxSpp) {
        return absl::InvalidArgumentError(absl::StrCat("spp ", s.spp, " is outside 1..", kMaxSpp));
    }
    if (s.tile < 1) return absl::InvalidArgumentError(absl::StrCat("tile ", s.tile, " is below 1"));
    if (s.passes < 1 || uint64_t(s.passes) > s.spp) {
        return absl::InvalidArgumentError(
            absl::StrCat("passes ", s.passes, " is outside 1..spp (", s.spp, ")"));
    }
    std::vector<RenderTask> tasks;
    for (int y = 0; y < s.height; y += s.tile) {
        for (int x = 0; x < s.width; x += s.tile) {
            const PixelRect rect{x, y, std::min(s.tile, s.width - x),
                                 std::min(s.tile, s.height - y)};
            for (int p = 0; p < s.passes; ++p) {
                tasks.push_back({int(tasks.size()), rect, s.spp * uint64_t(p) / uint64_t(s.passes),
                                 s.spp * uint64_t(p + 1) / uint64_t(s.passes)});
            }
        }
    }
    return tasks;
}

}  // namespace lf
