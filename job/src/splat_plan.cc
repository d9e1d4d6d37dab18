#include "lf/job/splat_plan.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "lf/job/plan.h"

namespace lf {

namespace {

constexpr uint64_t kMaxSplatTasks = uint64_t(1) << 22;

// Even and odd integers in [begin, end).
std::array<uint64_t, 2> Parities(uint64_t begin, uint64_t end) {
    const uint64_t n = end - begin;
    const uint64_t first = (n + 1) / 2, second = n / 2;  // begin's parity, then the other
    return (begin & 1) == 0 ? std::array<uint64_t, 2>{first, second}
                            : std::array<uint64_t, 2>{second, first};
}

// A plan is a vector in memory (and rows in the job store): refuse one of more than
// kMaxSplatTasks before making it.
absl::Status CheckTaskCount(uint64_t units, uint64_t per_task, size_t tiles = 1) {
    const uint64_t ranges = units / per_task + (units % per_task != 0);
    if (ranges > kMaxSplatTasks / tiles) {
        return absl::InvalidArgumentError(
            absl::StrCat(units, " in ranges of ", per_task,
                         (tiles > 1 ? absl::StrCat(" on ", tiles, " tiles") : ""),
                         " make more than ", kMaxSplatTasks, " tasks: raise the range per task"));
    }
    return absl::OkStatus();
}

}  // namespace

std::vector<PixelRect> SplatTiles(int width, int height, int tile) {
    std::vector<PixelRect> rects;
    for (int y = 0; y < height; y += tile) {
        for (int x = 0; x < width; x += tile) {
            rects.push_back({x, y, std::min(tile, width - x), std::min(tile, height - y)});
        }
    }
    return rects;
}

absl::StatusOr<std::vector<SplatTask>> PlanSplatRender(const SplatPlanSettings& s) {
    if (s.width <= 0 || s.height <= 0 || int64_t(s.width) * s.height >= (int64_t(1) << 31)) {
        return absl::InvalidArgumentError(absl::StrCat("image size ", s.width, "x", s.height,
                                                       " is empty or has 2^31 pixels or more"));
    }
    if (s.tile < 1) return absl::InvalidArgumentError(absl::StrCat("tile ", s.tile, " is below 1"));
    const uint64_t pixels = uint64_t(s.width) * uint64_t(s.height);
    std::vector<SplatTask> tasks;
    switch (s.kind) {
        case SplatPlanKind::kLightPaths: {
            // At most kMaxSpp per pixel-equivalent, like camera samples: the exact sums of a
            // pixel then stay as far from overflow as a path-traced pixel's.
            if (s.light_paths < 1 || s.light_paths / pixels > kMaxSpp) {
                return absl::InvalidArgumentError(
                    absl::StrCat("light paths ", s.light_paths, " is outside 1..", kMaxSpp,
                                 " per pixel of the ", s.width, "x", s.height, " frame"));
            }
            if (s.max_paths_per_task < 1) {
                return absl::InvalidArgumentError("light paths per task is 0");
            }
            if (absl::Status st = CheckTaskCount(s.light_paths, s.max_paths_per_task); !st.ok()) {
                return st;
            }
            for (uint64_t a = 0; a < s.light_paths; a += s.max_paths_per_task) {
                SplatTask t;
                t.index = int(tasks.size());
                t.path_begin = a;
                t.path_end = a + std::min(s.max_paths_per_task, s.light_paths - a);
                tasks.push_back(t);
            }
            break;
        }
        case SplatPlanKind::kCameraAndLight: {
            absl::StatusOr<std::vector<RenderTask>> tiles =
                PlanRender({s.width, s.height, s.spp, s.tile, s.passes});
            if (!tiles.ok()) return tiles.status();
            for (const RenderTask& r : *tiles) {
                tasks.push_back({r.index, r.rect, r.sample_begin, r.sample_end, 0, 0});
            }
            break;
        }
        case SplatPlanKind::kPhotonPasses: {
            if (s.spp < 1 || s.spp > kMaxSpp) {
                return absl::InvalidArgumentError(
                    absl::StrCat("photon passes ", s.spp, " is outside 1..", kMaxSpp));
            }
            if (s.max_paths_per_task < 1) {
                return absl::InvalidArgumentError("photon passes per task is 0");
            }
            const std::vector<PixelRect> rects = SplatTiles(s.width, s.height, s.tile);
            if (absl::Status st = CheckTaskCount(s.spp, s.max_paths_per_task, rects.size());
                !st.ok()) {
                return st;
            }
            for (const PixelRect& rect : rects) {
                for (uint64_t a = 0; a < s.spp; a += s.max_paths_per_task) {
                    const uint64_t b = a + std::min(s.max_paths_per_task, s.spp - a);
                    tasks.push_back({int(tasks.size()), rect, a, b, a, b});
                }
            }
            break;
        }
    }
    if (tasks.size() > size_t(INT32_MAX)) {
        return absl::InvalidArgumentError(absl::StrCat(tasks.size(), " tasks: too many"));
    }
    return tasks;
}

std::array<uint64_t, 2> SplatPaths(SplatPlanKind kind, const SplatTask& task) {
    switch (kind) {
        case SplatPlanKind::kLightPaths:
            return Parities(task.path_begin, task.path_end);
        case SplatPlanKind::kCameraAndLight: {
            const std::array<uint64_t, 2> per_pixel = Parities(task.sample_begin, task.sample_end);
            const uint64_t area = uint64_t(task.rect.Area());
            return {per_pixel[0] * area, per_pixel[1] * area};
        }
        case SplatPlanKind::kPhotonPasses:
            break;
    }
    return {0, 0};
}

}  // namespace lf
