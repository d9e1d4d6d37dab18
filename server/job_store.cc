#include "server/job_store.h"

#include <algorithm>

namespace lf {

uint64_t InMemoryJobStore::QueuePut(const JobRecord& job) {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_[job.id] = job;
    return 0;
}

absl::StatusOr<JobRecord> InMemoryJobStore::Get(const std::string& id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = jobs_.find(id);
    if (it == jobs_.end()) return absl::NotFoundError("no job " + id);
    return it->second;
}

std::optional<std::string> InMemoryJobStore::FindRequest(const std::string& request_id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [id, job] : jobs_) {
        if (job.spec.request_id == request_id) return id;
    }
    return std::nullopt;
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
