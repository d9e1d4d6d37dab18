// lightfarm-server's --retention: how long ended jobs are kept, as a duration with days.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"

namespace lf {

// "7d", "1d12h", "12h", "30m", "90s" (absl::ParseDuration's units, with days in front: `d`
// is 24 h), or "0" for forever (a zero duration). InvalidArgument, naming the form, otherwise:
// negative, a bare number other than 0, or an unknown unit.
absl::StatusOr<absl::Duration> ParseRetention(const std::string& text);

}  // namespace lf
