#include "server/worker_registry.h"

namespace lf {

void WorkerRegistry::Seen(const std::string& worker, absl::Time now) {
    auto it = by_worker_.find(worker);
    if (it == by_worker_.end()) {
        by_worker_.emplace(worker, by_seen_.emplace(now, worker));
        return;
    }
    by_seen_.erase(it->second);
    it->second = by_seen_.emplace(now, worker);
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
    return it != by_worker_.end() && now - it->second->first < alive_for_;
}

}  // namespace lf
