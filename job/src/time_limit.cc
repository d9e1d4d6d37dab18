#include "lf/job/time_limit.h"

namespace lf {

bool TimeLimitReached(const AdaptiveSettings& adaptive, absl::Time started, absl::Time now) {
    return adaptive.time_limit > 0 && started != absl::InfinitePast() &&
           now - started >= absl::Seconds(adaptive.time_limit);
}

}  // namespace lf
