#include "lf/server/speculation.h"

#include <algorithm>

namespace lf {

void SpeculationPolicy::TaskDone(absl::Duration took) {
    total_ += took;
    ++timed_;
}

absl::Duration SpeculationPolicy::Limit() const {
    return timed_ == 0 ? after_ : std::max(after_, 2 * total_ / timed_);
}

}  // namespace lf
