#include "lf/server/job_dependencies.h"

#include <algorithm>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/log.h"

namespace lf {

absl::StatusOr<std::vector<std::string>> CheckDependencyIds(
    const std::vector<std::string>& after, const std::string& what,
    const std::vector<std::string>& existing) {
    std::set<std::string> seen(existing.begin(), existing.end());
    std::vector<std::string> added;
    for (const std::string& id : after) {
        if (id.empty() || id.size() > kMaxDependencyIdBytes) {
            return absl::InvalidArgumentError(
                absl::StrCat(what, ": job id ", LogSafe(id, kMaxDependencyIdBytes), " of ",
                             id.size(), " bytes; expected 1 to ", kMaxDependencyIdBytes));
        }
        if (seen.insert(id).second) added.push_back(id);
    }
    if (seen.size() > kMaxDependencies) {
        return absl::InvalidArgumentError(absl::StrCat(
            what, ": ", seen.size(), " jobs to run after, above the limit of ", kMaxDependencies));
    }
    return added;
}

absl::Status CheckNewDependency(const DependencyState& dependency) {
    if (!dependency.state) {
        return absl::NotFoundError(absl::StrCat("dependency ", dependency.id, ": no such job"));
    }
    if (*dependency.state == JobState::kFailed || *dependency.state == JobState::kCancelled) {
        return absl::FailedPreconditionError(
            absl::StrCat("dependency ", dependency.id, " has already ended (",
                         JobStateName(*dependency.state), "): requeue it first"));
    }
    return absl::OkStatus();
}

std::optional<std::string> DependencyFailure(const DependencyState& dependency) {
    const std::string prefix = "dependency " + dependency.id;
    if (!dependency.state) return std::nullopt;
    switch (*dependency.state) {
        case JobState::kFailed:
            return absl::StrCat(prefix, " failed: ", dependency.error);
        case JobState::kCancelled:
            return prefix + " was cancelled";
        default:
            return std::nullopt;
    }
}

std::string WaitingForDependencies(const std::vector<DependencyState>& waiting) {
    std::vector<std::string> parts;
    for (const DependencyState& d : waiting) {
        parts.push_back(
            absl::StrCat(d.id, " (", d.state ? JobStateName(*d.state) : "unknown", ")"));
    }
    return "waiting for " + absl::StrJoin(parts, ", ");
}

std::optional<std::vector<std::string>> FindCycle(const std::string& job,
                                                  const std::vector<std::string>& added,
                                                  const DependenciesOf& after_of) {
    // Depth first from each added dependency, along what each job runs after, looking for `job`.
    std::set<std::string> visited;
    std::vector<std::string> path = {job};
    std::function<bool(const std::string&)> reaches = [&](const std::string& at) {
        path.push_back(at);
        if (at == job) return true;
        if (visited.insert(at).second) {
            for (const std::string& next : after_of(at)) {
                if (reaches(next)) return true;
            }
        }
        path.pop_back();
        return false;
    };
    for (const std::string& id : added) {
        if (reaches(id)) return path;
    }
    return std::nullopt;
}

std::string CycleText(const std::vector<std::string>& cycle) {
    return "cycle: " + absl::StrJoin(cycle, " -> ");
}

}  // namespace lf
