#include "lf/server/lease_table.h"

#include <climits>
#include <random>

namespace lf {

std::string RandomHex(int digits) {
    static const char kHex[] = "0123456789abcdef";
    std::random_device random;
    std::string hex;
    uint32_t bits = 0;
    for (int i = 0; i < digits; ++i, bits >>= 4) {
        if (i % 8 == 0) bits = random();
        hex.push_back(kHex[bits & 15]);
    }
    return hex;
}

std::string LeaseTable::Grant(const std::string& job_id, int task, int attempt,
                              const std::string& worker, absl::Time deadline) {
    std::string id = new_id_();
    while (by_id_.count(id)) id = new_id_();
    Entry& entry = by_id_[id];
    entry.lease = Lease{job_id, task, attempt, worker, deadline, true};
    entry.deadline = deadlines_.emplace(deadline, id);
    by_task_[{job_id, task}].push_back(id);
    return id;
}

const Lease* LeaseTable::Find(const std::string& lease_id) const {
    auto it = by_id_.find(lease_id);
    return it == by_id_.end() ? nullptr : &it->second.lease;
}

bool LeaseTable::Extend(const std::string& lease_id, absl::Time deadline) {
    auto it = by_id_.find(lease_id);
    if (it == by_id_.end() || !it->second.lease.current) return false;
    Entry& entry = it->second;
    deadlines_.erase(entry.deadline);
    entry.lease.deadline = deadline;
    entry.lease.heard = true;
    entry.deadline = deadlines_.emplace(deadline, lease_id);
    return true;
}

std::string PrincipalOf(const std::string& worker) {
    const size_t slash = worker.find('/');
    return slash == std::string::npos ? "" : worker.substr(0, slash);
}

int LeaseTable::CurrentOf(const std::string& principal) const {
    int n = 0;
    for (const auto& [deadline, id] : deadlines_)
        n += PrincipalOf(by_id_.at(id).lease.worker) == principal;
    return n;
}

std::set<std::string> LeaseTable::WorkersOf(const std::string& job_id) const {
    std::set<std::string> workers;
    for (const auto& [deadline, id] : deadlines_) {
        const Lease& lease = by_id_.at(id).lease;
        if (lease.job_id == job_id) workers.insert(lease.worker);
    }
    return workers;
}

void LeaseTable::EndEntry(Entry& entry) {
    if (!entry.lease.current) return;
    deadlines_.erase(entry.deadline);
    entry.lease.current = false;
}

void LeaseTable::End(const std::string& lease_id) {
    if (auto it = by_id_.find(lease_id); it != by_id_.end()) EndEntry(it->second);
}

void LeaseTable::EndTask(const std::string& job_id, int task) {
    auto it = by_task_.find({job_id, task});
    if (it == by_task_.end()) return;
    for (const std::string& id : it->second) EndEntry(by_id_.at(id));
}

std::vector<std::string> LeaseTable::TakeExpired(absl::Time now) {
    std::vector<std::string> expired;
    while (!deadlines_.empty() && deadlines_.begin()->first <= now) {
        expired.push_back(deadlines_.begin()->second);
        EndEntry(by_id_.at(expired.back()));
    }
    return expired;
}

void LeaseTable::ForgetJob(const std::string& job_id) {
    auto it = by_task_.lower_bound({job_id, INT_MIN});
    while (it != by_task_.end() && it->first.first == job_id) {
        for (const std::string& id : it->second) {
            auto entry = by_id_.find(id);
            EndEntry(entry->second);
            by_id_.erase(entry);
        }
        it = by_task_.erase(it);
    }
}

std::vector<const Lease*> LeaseTable::Current(const std::string& job_id, int task) const {
    std::vector<const Lease*> current;
    auto it = by_task_.find({job_id, task});
    if (it == by_task_.end()) return current;
    for (const std::string& id : it->second) {
        const Lease& lease = by_id_.at(id).lease;
        if (lease.current) current.push_back(&lease);
    }
    return current;
}

std::string LeaseTable::LastHolder(const std::string& job_id, int task) const {
    auto it = by_task_.find({job_id, task});
    if (it == by_task_.end() || it->second.empty()) return "";
    return by_id_.at(it->second.back()).lease.worker;
}

std::map<std::string, const Lease*> LeaseTable::CurrentByWorker() const {
    std::map<std::string, const Lease*> held;
    // Earliest deadline first: the one extended or granted last wins.
    for (const auto& [deadline, id] : deadlines_) {
        const Lease& lease = by_id_.at(id).lease;
        held[lease.worker] = &lease;
    }
    return held;
}

}  // namespace lf
