#include "server/job_store.h"

#include <algorithm>

namespace lf {

const char* JobStateName(JobState state) {
    switch (state) {
        case JobState::kQueued:
            return "queued";
        case JobState::kRunning:
            return "running";
        case JobState::kSucceeded:
            return "succeeded";
        case JobState::kFailed:
            return "failed";
        case JobState::kCancelled:
            return "cancelled";
    }
    return "unknown";
}

absl::Status InMemoryJobStore::Put(const JobRecord& job) {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_[job.id] = job;
    return absl::OkStatus();
}

absl::StatusOr<JobRecord> InMemoryJobStore::Get(const std::string& id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = jobs_.find(id);
    if (it == jobs_.end()) return absl::NotFoundError("no job " + id);
    return it->second;
}

std::vector<JobRecord> InMemoryJobStore::List() const {
    std::vector<JobRecord> jobs;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& [id, job] : jobs_) jobs.push_back(job);
    }
    std::sort(jobs.begin(), jobs.end(),
              [](const JobRecord& a, const JobRecord& b) { return a.seq > b.seq; });
    return jobs;
}

}  // namespace lf
