// The workers the scheduler has heard from lately, ordered by when each was last seen, so that
// forgetting the silent ones is cheap and the live ones are counted without a scan: any id a
// client makes up is kept only while it keeps calling. Each keeps what it said of itself at its
// last lease request (name, address, version), for `lightfarm workers`.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "absl/time/time.h"

namespace lf {

struct WorkerDescription {
    std::string name;               // lightfarm-worker --name, by default its host name
    std::string address;            // the peer of its last lease request, as gRPC names it
    std::string version;            // its build (lf::kBuildVersion)
    std::vector<std::string> tags;  // lightfarm-worker --tags (lf/job/worker_tags.h)
};

class WorkerRegistry {
  public:
    // A worker is live while it was seen less than `alive_for` ago (the lease); a silent one is
    // kept as offline (Offline) until `forget_after` since it was last seen.
    explicit WorkerRegistry(absl::Duration alive_for,
                            absl::Duration forget_after = absl::ZeroDuration())
        : alive_for_(alive_for), forget_after_(forget_after) {}

    // `about`, when given, replaces what the worker said of itself before.
    void Seen(const std::string& worker, absl::Time now, const WorkerDescription* about = nullptr);
    // Moves the workers not seen for `alive_for` by `now` to the offline ones, and forgets the
    // offline ones not seen for `forget_after`; returns how many fell silent.
    int ForgetSilent(absl::Time now);

    bool IsLive(const std::string& worker, absl::Time now) const;
    // What the worker said of itself at its last lease request; nullptr for one not kept.
    const WorkerDescription* AboutOf(const std::string& worker) const;
    // Whether some live worker has every one of `tags`.
    bool AnyLiveHas(const std::vector<std::string>& tags, absl::Time now) const;

    // A lease of the worker expired before any heartbeat for it: after kAbandonedInARow such in a
    // row the worker is quarantined (it gets no lease) until `now + quarantine`. Returns whether
    // this one quarantined it.
    bool Abandoned(const std::string& worker, absl::Time now, absl::Duration quarantine);
    // The worker heartbeated or sent a result: its abandoned leases in a row start again at 0.
    void Worked(const std::string& worker);
    bool IsQuarantined(const std::string& worker, absl::Time now) const;
    static constexpr int kAbandonedInARow = 3;
    // The workers kept: after ForgetSilent(now), the ones live at `now`.
    size_t size() const { return by_worker_.size(); }

    struct Entry {
        std::string id;
        WorkerDescription about;
        absl::Time last_seen;
        absl::Time quarantined_until = absl::InfinitePast();
    };
    // The workers kept, by id.
    std::vector<Entry> List() const;
    // The silent workers not yet forgotten, by id (quarantined_until unset).
    std::vector<Entry> Offline() const;
    // Past this many offline workers the longest silent is forgotten first: ids a client makes
    // up cost bounded memory.
    static constexpr size_t kMaxOffline = 4096;

  private:
    using BySeen = std::multimap<absl::Time, std::string>;
    struct Kept {
        BySeen::iterator seen;
        WorkerDescription about;
    };
    // Kept apart from by_worker_: a worker is silent, so forgotten there, by the time its lease
    // expires. Each entry is dropped once its quarantine ended and its last strike is as old.
    struct Strikes {
        int in_a_row = 0;
        absl::Time quarantined_until = absl::InfinitePast();
        absl::Time forget_at;
    };
    std::map<std::string, Strikes> strikes_;
    const absl::Duration alive_for_;
    const absl::Duration forget_after_;
    BySeen by_seen_;
    // The offline workers, by id and by when each was last seen (the oldest go first).
    struct Gone {
        WorkerDescription about;
        BySeen::iterator seen;
    };
    BySeen offline_by_seen_;
    std::map<std::string, Gone> offline_;
    std::map<std::string, Kept> by_worker_;
};

}  // namespace lf
