#include "lf/server/worker_registry.h"

#include <algorithm>

#include "lf/job/worker_tags.h"

namespace lf {

void WorkerRegistry::Seen(const std::string& worker, absl::Time now,
                          const WorkerDescription* about) {
    auto it = by_worker_.find(worker);
    if (it == by_worker_.end()) {
        it = by_worker_.emplace(worker, Kept{by_seen_.emplace(now, worker)}).first;
    } else {
        by_seen_.erase(it->second.seen);
        it->second.seen = by_seen_.emplace(now, worker);
    }
    if (about) it->second.about = *about;
    if (auto gone = offline_.find(worker); gone != offline_.end()) {
        if (!about) it->second.about = std::move(gone->second.about);
        offline_by_seen_.erase(gone->second.seen);
        offline_.erase(gone);
    }
}

int WorkerRegistry::ForgetSilent(absl::Time now) {
    int forgotten = 0;
    while (!by_seen_.empty() && now - by_seen_.begin()->first >= alive_for_) {
        auto it = by_worker_.find(by_seen_.begin()->second);
        offline_[it->first] = {std::move(it->second.about),
                               offline_by_seen_.emplace(by_seen_.begin()->first, it->first)};
        by_worker_.erase(it);
        by_seen_.erase(by_seen_.begin());
        ++forgotten;
    }
    while (!offline_by_seen_.empty() && (offline_.size() > kMaxOffline ||
                                         now - offline_by_seen_.begin()->first >= forget_after_)) {
        offline_.erase(offline_by_seen_.begin()->second);
        offline_by_seen_.erase(offline_by_seen_.begin());
    }
    std::erase_if(strikes_, [now](const auto& entry) { return now >= entry.second.forget_at; });
    return forgotten;
}

bool WorkerRegistry::IsLive(const std::string& worker, absl::Time now) const {
    auto it = by_worker_.find(worker);
    return it != by_worker_.end() && now - it->second.seen->first < alive_for_;
}

const WorkerDescription* WorkerRegistry::AboutOf(const std::string& worker) const {
    auto it = by_worker_.find(worker);
    return it == by_worker_.end() ? nullptr : &it->second.about;
}

bool WorkerRegistry::AnyLiveHas(const std::vector<std::string>& tags, absl::Time now) const {
    return std::any_of(by_worker_.begin(), by_worker_.end(), [&](const auto& entry) {
        return now - entry.second.seen->first < alive_for_ &&
               HasAllTags(entry.second.about.tags, tags);
    });
}

bool WorkerRegistry::Abandoned(const std::string& worker, absl::Time now,
                               absl::Duration quarantine) {
    Strikes& s = strikes_[worker];
    s.forget_at = std::max(s.quarantined_until, now + quarantine);
    if (++s.in_a_row < kAbandonedInARow) return false;
    s.in_a_row = 0;
    s.quarantined_until = s.forget_at = now + quarantine;
    return true;
}

void WorkerRegistry::Worked(const std::string& worker) { strikes_.erase(worker); }

bool WorkerRegistry::IsQuarantined(const std::string& worker, absl::Time now) const {
    auto it = strikes_.find(worker);
    return it != strikes_.end() && now < it->second.quarantined_until;
}

std::vector<WorkerRegistry::Entry> WorkerRegistry::List() const {
    std::vector<Entry> entries;
    entries.reserve(by_worker_.size());
    for (const auto& [id, kept] : by_worker_) {
        auto strikes = strikes_.find(id);
        entries.push_back(
            {id, kept.about, kept.seen->first,
             strikes == strikes_.end() ? absl::InfinitePast() : strikes->second.quarantined_until});
    }
    return entries;
}

std::vector<WorkerRegistry::Entry> WorkerRegistry::Offline() const {
    std::vector<Entry> entries;
    entries.reserve(offline_.size());
    for (const auto& [id, gone] : offline_) entries.push_back({id, gone.about, gone.seen->first});
    return entries;
}

}  // namespace lf
