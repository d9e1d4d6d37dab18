#include "lf/job/adaptive_tile_execution.h"

#include "absl/strings/str_cat.h"
#include "lf/job/time_limit.h"

namespace lf {

absl::StatusOr<std::unique_ptr<AdaptiveTileExecution>> AdaptiveTileExecution::Make(
    int width, int height, uint64_t first_spp, int tile, const AdaptiveSettings& settings,
    uint64_t max_task_samples, const TileStoreFactory& tile_stores, uint32_t aovs) {
    absl::StatusOr<std::unique_ptr<AdaptiveTilePlan>> plan = AdaptiveTilePlan::Make(
        width, height, first_spp, tile, settings, max_task_samples, tile_stores, aovs);
    if (!plan.ok()) return plan.status();
    return std::unique_ptr<AdaptiveTileExecution>(
        new AdaptiveTileExecution(std::move(*plan), settings));
}

AdaptiveTileExecution::AdaptiveTileExecution(std::unique_ptr<AdaptiveTilePlan> plan,
                                             const AdaptiveSettings& settings)
    : TileExecution(std::move(plan), 0), settings_(settings) {}

std::string AdaptiveTileExecution::Summary() const {
    return absl::StrCat(
        plan().tile_count(), " tiles, ", plan().width(), "x", plan().height(), ", first pass ",
        plan().first_spp(), " spp, adaptive up to ", settings_.max_spp, " spp, ",
        settings_.noise_threshold > 0 ? absl::StrCat("noise threshold ", settings_.noise_threshold)
                                      : absl::StrCat("target error ", settings_.target_error),
        ", time limit ", settings_.time_limit, " s");
}

std::vector<int> AdaptiveTileExecution::Start() {
    std::vector<int> pending;
    for (int t = 0; t < int(task_count()); ++t) {
        if (plan().IsPending(t)) pending.push_back(t);
    }
    return pending;
}

uint64_t AdaptiveTileExecution::QueueRank(int task) const {
    return plan().tasks()[size_t(task)].sample_begin;
}

std::optional<std::vector<int>> AdaptiveTileExecution::EnforceTimeLimit(absl::Time started,
                                                                        absl::Time now) {
    if (plan().stopped() || !TimeLimitReached(settings_, started, now)) return std::nullopt;
    std::vector<int> dropped = plan().Stop();
    dropped_ += int(dropped.size());
    return dropped;
}

std::optional<absl::Duration> AdaptiveTileExecution::time_limit() const {
    if (settings_.time_limit <= 0) return std::nullopt;
    return absl::Seconds(settings_.time_limit);
}

}  // namespace lf
