#include "lf/server/blocklist.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "lf/core/plural.h"

namespace lf {

bool CountWorkerFailure(JobRecord& job, const std::string& worker, const std::string& error) {
    auto it = std::find_if(job.worker_failures.begin(), job.worker_failures.end(),
                           [&](const WorkerFailures& w) { return w.worker == worker; });
    if (it == job.worker_failures.end()) {
        it = job.worker_failures.insert(it, WorkerFailures{worker, 0, ""});
    }
    ++it->failures;
    it->last_error = error;
    return it->failures == job.spec.blocklist_after;
}

bool IsBlocklisted(const JobRecord& job, const std::string& worker) {
    return std::any_of(job.worker_failures.begin(), job.worker_failures.end(),
                       [&](const WorkerFailures& w) {
                           return w.worker == worker && w.failures >= job.spec.blocklist_after;
                       });
}

std::string BlocklistText(const std::vector<WorkerFailures>& blocked) {
    std::string text;
    for (const WorkerFailures& w : blocked) {
        absl::StrAppend(&text, text.empty() ? "" : ", ", w.worker, " (",
                        Plural(w.failures, "failure"), ", last: ", w.last_error, ")");
    }
    return text;
}

std::optional<std::string> StrandedError(const JobRecord& job,
                                         const std::vector<std::string>& live) {
    if (live.empty()) return std::nullopt;
    for (const std::string& worker : live) {
        if (!IsBlocklisted(job, worker)) return std::nullopt;
    }
    return absl::StrCat("every live worker is blocklisted from the job: ",
                        BlocklistText(job.Blocklisted()));
}

}  // namespace lf
