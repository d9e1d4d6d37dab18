// Speculation policy: near the end of a job, a task running much longer than the job's others is
// leased a second time to an idle worker, and the first result wins (both are the same bits), so
// one slow worker does not hold the job.
#pragma once

#include "absl/time/time.h"

namespace lf {

class SpeculationPolicy {
  public:
    // A task is a straggler once it has run `after` and twice the job's mean task time.
    explicit SpeculationPolicy(absl::Duration after) : after_(after) {}

    // A task of the job took `took`, from lease to result.
    void TaskDone(absl::Duration took);
    // How long a task of the job runs before it is a straggler.
    absl::Duration Limit() const;
    bool IsStraggler(absl::Duration running) const { return running >= Limit(); }

  private:
    absl::Duration after_;
    absl::Duration total_ = absl::ZeroDuration();
    int timed_ = 0;
};

}  // namespace lf
