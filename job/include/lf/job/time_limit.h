// Adaptive time limit policy: an adaptive job samples until its time limit, counted from when it
// started running; then its passes not yet merged are dropped and the tiles keep what they have.
#pragma once

#include "absl/time/time.h"
#include "lf/job/job_spec.h"

namespace lf {

// Whether a job that started at `started` (InfinitePast: not yet) with these settings has
// reached its time limit at `now`. A limit of 0 is none.
bool TimeLimitReached(const AdaptiveSettings& adaptive, absl::Time started, absl::Time now);

}  // namespace lf
