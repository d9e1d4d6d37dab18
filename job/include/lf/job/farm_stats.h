// The farm's history as `lightfarm stats` reports it (issue 30): jobs, tasks, samples and times
// per owner and per worker since some time. Plain logic: the coordinator's store sums its rows
// in SQL and adds the sums up here; the CLI parses --since here.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/job/job_record.h"

namespace lf {

struct StatsQuery {
    absl::Time since = absl::InfinitePast();  // work that ended at or after this
    // Only this owner's jobs, and the workers' rows of their tasks only; nullopt: everyone's.
    std::optional<std::string> owner;
};

struct OwnerStats {
    std::string owner;
    // Jobs that ended in the window by final state, and those queued or running now.
    int64_t succeeded = 0, failed = 0, cancelled = 0, active = 0;
    int64_t tasks = 0;  // tasks merged
    uint64_t samples = 0;
    TaskTimes times;
    friend bool operator==(const OwnerStats&, const OwnerStats&) = default;
};

struct WorkerStats {
    std::string worker;
    int64_t tasks = 0;     // tasks merged
    int64_t failures = 0;  // counted task failures, of jobs that ended in the window
    TaskTimes times;
    friend bool operator==(const WorkerStats&, const WorkerStats&) = default;
};

struct FarmStats {
    absl::Time since = absl::InfinitePast();
    std::vector<OwnerStats> owners;    // by name
    std::vector<WorkerStats> workers;  // by name
};

// Adds up rows of history, each one job or task or a group of them already summed, into one
// line per owner and per worker.
class StatsAccumulator {
  public:
    // `count` jobs of `owner` in `state` (a final state: ended; queued or running: active).
    void AddJobs(std::string_view owner, JobState state, int64_t count);
    void AddTasks(std::string_view owner, std::string_view worker, int64_t tasks, uint64_t samples,
                  const TaskTimes& times);
    void AddFailures(std::string_view worker, int64_t failures);
    FarmStats Take(absl::Time since) &&;

  private:
    OwnerStats& Owner(std::string_view owner);
    WorkerStats& Worker(std::string_view worker);
    std::map<std::string, OwnerStats, std::less<>> owners_;
    std::map<std::string, WorkerStats, std::less<>> workers_;
};

// The start of a stats window: "7d", "24h", "30m", "45s" before `now` (a positive whole number
// and a unit), or a date "2026-11-01" (midnight UTC) or an RFC 3339 time. InvalidArgument naming
// the text for anything else and for a start after `now`.
absl::StatusOr<absl::Time> ParseSince(std::string_view text, absl::Time now);

}  // namespace lf
