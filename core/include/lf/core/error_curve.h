// Error-against-time curves of renders (one point per rung of a spp ladder) compared at equal
// time: `lightfarm converge` asks how much less error one configuration has than another for
// the same wall-clock time, but their rungs land at different times, so each curve is
// interpolated between its own points, as a power law (log error linear in log time), the form
// Monte Carlo error takes (docs/convergence.md).
#pragma once

#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace lf {

// (seconds, error) points, in any order; both positive.
using ErrorCurve = std::vector<std::pair<double, double>>;

struct TimeRange {
    double from = 0, to = 0;  // seconds, from <= to
};

// The times every curve covers: from the latest first point to the earliest last point.
// InvalidArgument when there is no curve, a curve is empty or has a non-positive value, or the
// curves share no time.
absl::StatusOr<TimeRange> CommonTimeRange(const std::vector<ErrorCurve>& curves);

// The curve's error at `seconds`: log error interpolated linearly in log time between the two
// points around it (exact for a power law). InvalidArgument outside the curve's times.
absl::StatusOr<double> ErrorAtTime(const ErrorCurve& curve, double seconds);

// The typical ratio b(t) / a(t) over `range`: exp of the mean of log(b(t) / a(t)) over log t.
// Both logs are piecewise linear in log t, so the mean is exact (the trapezoid rule on the union
// of both curves' points inside the range). A range of one time gives the ratio there.
// InvalidArgument when a curve does not cover the range.
absl::StatusOr<double> MeanRatioOverTime(const ErrorCurve& a, const ErrorCurve& b, TimeRange range);

}  // namespace lf
