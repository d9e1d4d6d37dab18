#include "lf/job/job_execution.h"

#include "lf/job/adaptive_tile_execution.h"
#include "lf/job/shot_execution.h"
#include "lf/job/splat_execution.h"
#include "lf/job/splat_settings.h"
#include "lf/job/sweep_execution.h"
#include "lf/job/tile_execution.h"

namespace lf {

absl::StatusOr<std::vector<int>> JobExecution::Publish(bool converged, const std::string& hash,
                                                       std::shared_ptr<const std::string> bytes) {
    return absl::FailedPreconditionError("not a job solved in sweeps");
}

namespace {

template <class Kind>
absl::StatusOr<std::unique_ptr<JobExecution>> Upcast(absl::StatusOr<std::unique_ptr<Kind>> made) {
    if (!made.ok()) return made.status();
    return std::unique_ptr<JobExecution>(std::move(*made));
}

}  // namespace

absl::StatusOr<std::unique_ptr<JobExecution>> MakeJobExecution(
    const JobSpec& spec, const TileStoreFactory& tile_stores) {
    if (spec.shot.frames) return Upcast(ShotExecution::Make(spec, tile_stores));
    return MakeFrameExecution(spec, tile_stores);
}

// The one place that tells the kinds of image apart.
absl::StatusOr<std::unique_ptr<JobExecution>> MakeFrameExecution(
    const JobSpec& spec, const TileStoreFactory& tile_stores) {
    if (UsesSplatPlan(spec.method)) {
        // The plan local mode makes of the same settings (lf::RenderSplatImage), so the merged
        // sums are its bits.
        absl::StatusOr<SplatPlanSettings> plan = SplatPlanSettingsOf(spec.method, spec.plan);
        if (!plan.ok()) return plan.status();
        return Upcast(SplatExecution::Make(*plan, tile_stores));
    }
    if (IsAdaptive(spec.adaptive)) {
        return Upcast(AdaptiveTileExecution::Make(spec.plan.width, spec.plan.height, spec.plan.spp,
                                                  spec.plan.tile, spec.adaptive, kMaxTaskSamples,
                                                  tile_stores, spec.aovs));
    }
    if (SolvedInSweeps(spec)) {
        return Upcast(SweepExecution::Make(spec.plan, spec.radiosity, tile_stores, spec.aovs));
    }
    return Upcast(TileExecution::Make(spec.plan, tile_stores, spec.aovs));
}

}  // namespace lf
