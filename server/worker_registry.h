// The workers the scheduler has heard from lately, ordered by when each was last seen, so that
// forgetting the silent ones is cheap and the live ones are counted without a scan: any id a
// client makes up is kept only while it keeps calling.
#pragma once

#include <map>
#include <string>

#include "absl/time/time.h"

namespace lf {

class WorkerRegistry {
  public:
    // A worker is live while it was seen less than `alive_for` ago (the lease).
    explicit WorkerRegistry(absl::Duration alive_for) : alive_for_(alive_for) {}

    void Seen(const std::string& worker, absl::Time now);
    // Forgets the workers not seen for `alive_for` by `now`; returns how many.
    int ForgetSilent(absl::Time now);

    bool IsLive(const std::string& worker, absl::Time now) const;
    // The workers kept: after ForgetSilent(now), the ones live at `now`.
    size_t size() const { return by_worker_.size(); }

  private:
    const absl::Duration alive_for_;
    std::multimap<absl::Time, std::string> by_seen_;
    std::map<std::string, std::multimap<absl::Time, std::string>::iterator> by_worker_;
};

}  // namespace lf
