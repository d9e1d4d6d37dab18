#include "lf/server/ended_jobs.h"

#include "lf/core/log.h"

namespace lf {

const JobRecord& EndedJobs::Add(JobRecord record, uint64_t ticket) {
    const std::string id = record.id;
    to_settle_.push_back(id);
    Ending& ending = ending_[id];
    ending = Ending{std::move(record), ticket};
    return ending.record;
}

const JobRecord* EndedJobs::Find(const std::string& job_id) const {
    if (auto it = ending_.find(job_id); it != ending_.end()) return &it->second.record;
    if (auto it = unrecorded_.find(job_id); it != unrecorded_.end()) return &it->second;
    return nullptr;
}

std::optional<std::pair<std::string, uint64_t>> EndedJobs::FindRequest(
    const std::string& request_id) const {
    for (const auto& [id, ending] : ending_) {
        if (ending.record.spec.request_id == request_id) return std::pair{id, ending.ticket};
    }
    for (const auto& [id, record] : unrecorded_) {
        if (record.spec.request_id == request_id) return std::pair{id, uint64_t(0)};
    }
    return std::nullopt;
}

void EndedJobs::AddBlobsInUse(std::set<std::string>& hashes) const {
    auto add = [&](const JobRecord& record) {
        hashes.insert(record.spec.scene.hash);
        for (const BlobRef& file : record.spec.files) hashes.insert(file.hash);
    };
    for (const auto& [id, ending] : ending_) add(ending.record);
    for (const auto& [id, record] : unrecorded_) add(record);
}

std::vector<std::pair<std::string, uint64_t>> EndedJobs::TakeUnsettled() {
    std::vector<std::pair<std::string, uint64_t>> unsettled;
    for (const std::string& id : to_settle_) unsettled.emplace_back(id, ending_.at(id).ticket);
    to_settle_.clear();
    return unsettled;
}

void EndedJobs::Settle(const std::string& job_id, const absl::Status& durable) {
    auto it = ending_.find(job_id);
    if (it == ending_.end()) return;
    if (!durable.ok()) {
        NamedLogger("scheduler")
            ->error("job={} ended ({}) but not recorded: {}", job_id,
                    JobStateName(it->second.record.state), std::string(durable.message()));
        // The store, which says it runs, has it run again after a restart.
        unrecorded_[job_id] = std::move(it->second.record);
    }
    ending_.erase(it);
}

}  // namespace lf
