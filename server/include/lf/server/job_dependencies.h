// Job dependencies (issue 30, `lightfarm submit --after`, `lightfarm depend`): the plain rules,
// without the scheduler. A job waits while a job it runs after is queued or running, runs once
// every one has succeeded, and fails when one fails or is cancelled; the scheduler applies these
// to the jobs it holds (lf/server/scheduler.h). A job is deleted (or expires) only once ended,
// when its dependents were settled already (failed with it, or released by its success, durably
// before the delete: the store writes in order), so a dependency gone from the store fails
// nothing: it counts as ended and settled.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/job/job_record.h"

namespace lf {

// The most jobs one job runs after, and the longest id accepted (ids are "job-" and 20 hex).
inline constexpr size_t kMaxDependencies = 64;
inline constexpr size_t kMaxDependencyIdBytes = 64;

// A dependency as the farm knows it now: nullopt `state` for a job the farm does not hold
// (never submitted, or deleted once ended).
struct DependencyState {
    std::string id;
    std::optional<JobState> state;
    std::string error;  // a failed job's
};

// `after` without repeats, in first-seen order; InvalidArgument naming `what` ("--after") for
// an empty or over-long id, or more than kMaxDependencies distinct ids (counted after
// `existing`, those the job has already, which are left out of the result).
absl::StatusOr<std::vector<std::string>> CheckDependencyIds(
    const std::vector<std::string>& after, const std::string& what,
    const std::vector<std::string>& existing = {});

// Whether a new dependency may be taken: NotFound naming an unknown id, FailedPrecondition
// naming one that failed or was cancelled and its state; Ok for a queued, running or succeeded
// one.
absl::Status CheckNewDependency(const DependencyState& dependency);

// Why a job running after `dependency` fails, when that ended without succeeding:
// "dependency job-1 failed: <its error>", "dependency job-1 was cancelled"; nullopt while it is
// queued or running, once it succeeded, and once it is gone (see above).
std::optional<std::string> DependencyFailure(const DependencyState& dependency);

// The waiting reason of a job whose dependencies `waiting` are not ended:
// "waiting for job-1 (running), job-2 (queued)".
std::string WaitingForDependencies(const std::vector<DependencyState>& waiting);

// The cycle that making `job` run after `added` would close, through the jobs that still wait
// (`after_of` gives a job's dependencies, none for an ended one): {job, added[i], ..., job};
// nullopt when there is none. `job` in `added` itself is the cycle {job, job}.
using DependenciesOf = std::function<std::vector<std::string>(const std::string& job)>;
std::optional<std::vector<std::string>> FindCycle(const std::string& job,
                                                  const std::vector<std::string>& added,
                                                  const DependenciesOf& after_of);
// "cycle: A -> B -> A".
std::string CycleText(const std::vector<std::string>& cycle);

}  // namespace lf
