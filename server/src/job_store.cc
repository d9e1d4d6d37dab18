#include "lf/server/job_store.h"

#include <algorithm>

#include "absl/strings/str_cat.h"

namespace lf {

namespace {

// Whether `job` passes the query's filters (not its limit).
bool Matches(const JobQuery& query, const JobRecord& job) {
    if (query.before_seq != 0 && job.seq >= query.before_seq) return false;
    if (query.owner && job.spec.owner != *query.owner) return false;
    if (query.ended_before == absl::InfinitePast()) return true;
    return IsFinal(job.state) && job.finished < query.ended_before;
}

}  // namespace

uint64_t InMemoryJobStore::QueuePut(const JobRecord& job) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!job.spec.request_id.empty()) {
        for (const auto& [id, other] : jobs_) {
            if (id != job.id && other.spec.request_id == job.spec.request_id) {
                refused_[++last_refused_] = absl::AlreadyExistsError(
                    absl::StrCat("job store: request id ", job.spec.request_id, " of job ", job.id,
                                 " is job ", id, "'s"));
                return last_refused_;
            }
        }
    }
    jobs_[job.id] = job;
    return kDone;
}

uint64_t InMemoryJobStore::QueueDelete(const std::string& id) {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.erase(id);
    return kDone;
}

absl::Status InMemoryJobStore::WaitDurable(uint64_t ticket) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = refused_.find(ticket);
    return it == refused_.end() ? absl::OkStatus() : it->second;
}

absl::StatusOr<JobRecord> InMemoryJobStore::Get(const std::string& id) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = jobs_.find(id);
    if (it == jobs_.end()) return absl::NotFoundError("no job " + id);
    return it->second;
}

absl::StatusOr<std::optional<std::string>> InMemoryJobStore::FindRequest(
    const std::string& request_id) const {
    if (request_id.empty()) return std::nullopt;
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [id, job] : jobs_) {
        if (job.spec.request_id == request_id) return id;
    }
    return std::nullopt;
}

absl::StatusOr<std::vector<JobRecord>> InMemoryJobStore::List(const JobQuery& query) const {
    std::vector<JobRecord> jobs;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& [id, job] : jobs_) {
            if (Matches(query, job)) jobs.push_back(job);
        }
    }
    std::sort(jobs.begin(), jobs.end(),
              [](const JobRecord& a, const JobRecord& b) { return a.seq > b.seq; });
    if (query.limit != 0 && jobs.size() > query.limit) jobs.resize(query.limit);
    return jobs;
}

}  // namespace lf
