#include "lf/server/worker_registry.h"

namespace lf {

void WorkerRegistry::Seen(const std::string& worker, absl::Time now,
                          const WorkerDescription* about) {
    auto it = by_worker_.find(worker);
    if (it == by_worker_.end()) {
        it = by_worker_.emplace(worker, Kept{by_seen_.emplace(now, worker), {}}).first;
    } else {
        by_seen_.erase(it->second.seen);
        it->second.seen = by_seen_.emplace(now, worker);
    }
    if (about) it->second.about = *about;
}

int WorkerRegistry::ForgetSilent(absl::Time now) {
    int forgotten = 0;
    while (!by_seen_.empty() && now - by_seen_.begin()->first >= alive_for_) {
        by_worker_.erase(by_seen_.begin()->second);
        by_seen_.erase(by_seen_.begin());
        ++forgotten;
    }
    return forgotten;
}

bool WorkerRegistry::IsLive(const std::string& worker, absl::Time now) const {
    auto it = by_worker_.find(worker);
    return it != by_worker_.end() && now - it->second.seen->first < alive_for_;
}

std::vector<WorkerRegistry::Entry> WorkerRegistry::List() const {
    std::vector<Entry> entries;
    entries.reserve(by_worker_.size());
    for (const auto& [id, kept] : by_worker_) {
        entries.push_back({id, kept.about, kept.seen->first});
    }
    return entries;
}

}  // namespace lf
