#include "lf/job/farm_stats.h"

#include <utility>

#include "absl/algorithm/container.h"
#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"

namespace lf {

OwnerStats& StatsAccumulator::Owner(std::string_view owner) {
    auto it = owners_.find(owner);
    if (it == owners_.end()) {
        it = owners_.emplace(std::string(owner), OwnerStats{.owner = std::string(owner)}).first;
    }
    return it->second;
}

WorkerStats& StatsAccumulator::Worker(std::string_view worker) {
    auto it = workers_.find(worker);
    if (it == workers_.end()) {
        it =
            workers_.emplace(std::string(worker), WorkerStats{.worker = std::string(worker)}).first;
    }
    return it->second;
}

void StatsAccumulator::AddJobs(std::string_view owner, JobState state, int64_t count) {
    OwnerStats& o = Owner(owner);
    switch (state) {
        case JobState::kSucceeded:
            o.succeeded += count;
            break;
        case JobState::kFailed:
            o.failed += count;
            break;
        case JobState::kCancelled:
            o.cancelled += count;
            break;
        case JobState::kQueued:
        case JobState::kRunning:
            o.active += count;
            break;
    }
}

void StatsAccumulator::AddTasks(std::string_view owner, std::string_view worker, int64_t tasks,
                                uint64_t samples, const TaskTimes& times) {
    OwnerStats& o = Owner(owner);
    o.tasks += tasks;
    o.samples += samples;
    o.times += times;
    WorkerStats& w = Worker(worker);
    w.tasks += tasks;
    w.times += times;
}

void StatsAccumulator::AddFailures(std::string_view worker, int64_t failures) {
    Worker(worker).failures += failures;
}

FarmStats StatsAccumulator::Take(absl::Time since) && {
    FarmStats stats{.since = since};
    for (auto& [name, o] : owners_) stats.owners.push_back(std::move(o));
    for (auto& [name, w] : workers_) stats.workers.push_back(std::move(w));
    return stats;
}

absl::StatusOr<absl::Time> ParseSince(std::string_view text, absl::Time now) {
    const auto refuse = [&](std::string_view why) {
        return absl::InvalidArgumentError(
            absl::StrCat("--since ", std::string(text), ": ", std::string(why),
                         " (a duration such as 7d, 24h, 30m, 45s, or a date 2026-11-01 or time "
                         "2026-11-01T08:00:00Z)"));
    };
    absl::Time since;
    std::string error;
    if (!text.empty() && text.front() >= '0' && text.front() <= '9' &&
        text.find('-') == std::string_view::npos) {
        static const std::pair<char, absl::Duration> kUnits[] = {{'d', absl::Hours(24)},
                                                                 {'h', absl::Hours(1)},
                                                                 {'m', absl::Minutes(1)},
                                                                 {'s', absl::Seconds(1)}};
        int64_t count = 0;
        const absl::Duration* unit = nullptr;
        for (const auto& [letter, duration] : kUnits) {
            if (text.back() == letter) unit = &duration;
        }
        const std::string_view digits = text.substr(0, text.size() - 1);
        if (!unit || !absl::c_all_of(digits, absl::ascii_isdigit) ||
            !absl::SimpleAtoi(std::string(digits), &count) || count <= 0) {
            return refuse("not a positive whole number of d, h, m or s");
        }
        // Beyond a million days any window is everything; the cap keeps the product finite.
        if (count > 1000000LL * 86400) return refuse("too long a duration");
        since = now - count * *unit;
    } else if (absl::ParseTime("%Y-%m-%d", std::string(text), absl::UTCTimeZone(), &since,
                               &error) ||
               absl::ParseTime(absl::RFC3339_full, std::string(text), &since, &error)) {
        if (since > now) return refuse("in the future");
    } else {
        return refuse("not a duration, date or time");
    }
    return since;
}

}  // namespace lf
