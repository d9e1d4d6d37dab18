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
    std::string name;     // lightfarm-worker --name, by default its host name
    std::string address;  // the peer of its last lease request, as gRPC names it
    std::string version;  // its build (lf::kBuildVersion)
};

class WorkerRegistry {
  public:
    // A worker is live while it was seen less than `alive_for` ago (the lease).
    explicit WorkerRegistry(absl::Duration alive_for) : alive_for_(alive_for) {}

    // `about`, when given, replaces what the worker said of itself before.
    void Seen(const std::string& worker, absl::Time now, const WorkerDescription* about = nullptr);
    // Forgets the workers not seen for `alive_for` by `now`; returns how many.
    int ForgetSilent(absl::Time now);

    bool IsLive(const std::string& worker, absl::Time now) const;

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
    BySeen by_seen_;
    std::map<std::string, Kept> by_worker_;
};

}  // namespace lf
