// Deadlines of live leases, earliest first: the timeout checker's bookkeeping, apart from the
// scheduler so it can be tested with made-up times.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "absl/time/time.h"

namespace lf {

class LeaseTimeouts {
  public:
    void Set(const std::string& lease_id, absl::Time deadline);  // adds or moves
    void Remove(const std::string& lease_id);
    // Removes and returns the leases whose deadline is at or before `now`, earliest first.
    std::vector<std::string> TakeExpired(absl::Time now);
    size_t size() const { return by_id_.size(); }
    std::vector<std::string> lease_ids() const;  // by id

  private:
    std::multimap<absl::Time, std::string> by_deadline_;
    std::map<std::string, std::multimap<absl::Time, std::string>::iterator> by_id_;
};

}  // namespace lf
