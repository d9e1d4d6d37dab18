#include "server/lease_timeouts.h"

namespace lf {

void LeaseTimeouts::Set(const std::string& lease_id, absl::Time deadline) {
    Remove(lease_id);
    by_id_[lease_id] = by_deadline_.emplace(deadline, lease_id);
}

void LeaseTimeouts::Remove(const std::string& lease_id) {
    auto it = by_id_.find(lease_id);
    if (it == by_id_.end()) return;
    by_deadline_.erase(it->second);
    by_id_.erase(it);
}

std::vector<std::string> LeaseTimeouts::TakeExpired(absl::Time now) {
    std::vector<std::string> expired;
    while (!by_deadline_.empty() && by_deadline_.begin()->first <= now) {
        expired.push_back(by_deadline_.begin()->second);
        by_id_.erase(expired.back());
        by_deadline_.erase(by_deadline_.begin());
    }
    return expired;
}

std::vector<std::string> LeaseTimeouts::lease_ids() const {
    std::vector<std::string> ids;
    ids.reserve(by_id_.size());
    for (const auto& [id, deadline] : by_id_) ids.push_back(id);
    return ids;
}

}  // namespace lf
