#include "lf/core/error_curve.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace lf {

namespace {

// (log seconds, log error), sorted by time.
using LogCurve = std::vector<std::pair<double, double>>;

absl::StatusOr<LogCurve> ToLog(const ErrorCurve& curve) {
    if (curve.empty()) return absl::InvalidArgumentError("an error curve without points");
    LogCurve out;
    for (const auto& [seconds, error] : curve) {
        if (!(seconds > 0) || !(error > 0)) {
            return absl::InvalidArgumentError(
                absl::StrCat("error curve point (", seconds, " s, ", error, "): both must be > 0"));
        }
        out.push_back({std::log(seconds), std::log(error)});
    }
    std::sort(out.begin(), out.end());
    return out;
}

// Within [front, back] of `curve` (the caller checks).
double LogErrorAt(const LogCurve& curve, double u) {
    auto hi = std::lower_bound(curve.begin(), curve.end(), u,
                               [](const auto& p, double x) { return p.first < x; });
    if (hi == curve.begin()) return hi->second;
    if (hi == curve.end()) return curve.back().second;
    auto lo = std::prev(hi);
    if (hi->first == lo->first) return lo->second;
    const double w = (u - lo->first) / (hi->first - lo->first);
    return lo->second + w * (hi->second - lo->second);
}

// A relative tolerance on log times, so a range computed from a curve's own points is inside it
// despite rounding in exp(log(t)).
constexpr double kLogSlack = 1e-12;

absl::Status CheckCovers(const LogCurve& curve, double u, const char* which) {
    if (u < curve.front().first - kLogSlack || u > curve.back().first + kLogSlack) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s %.6g s is outside the curve's %.6g to %.6g s", which, std::exp(u),
                            std::exp(curve.front().first), std::exp(curve.back().first)));
    }
    return absl::OkStatus();
}

}  // namespace

absl::StatusOr<TimeRange> CommonTimeRange(const std::vector<ErrorCurve>& curves) {
    if (curves.empty()) return absl::InvalidArgumentError("no error curves to compare");
    TimeRange range{0, std::numeric_limits<double>::infinity()};
    for (const ErrorCurve& curve : curves) {
        absl::StatusOr<LogCurve> log_curve = ToLog(curve);
        if (!log_curve.ok()) return log_curve.status();
        range.from = std::max(range.from, std::exp(log_curve->front().first));
        range.to = std::min(range.to, std::exp(log_curve->back().first));
    }
    if (range.from > range.to) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "the curves share no time: one starts at %.6g s, after another ends at %.6g s",
            range.from, range.to));
    }
    return range;
}

absl::StatusOr<double> ErrorAtTime(const ErrorCurve& curve, double seconds) {
    absl::StatusOr<LogCurve> log_curve = ToLog(curve);
    if (!log_curve.ok()) return log_curve.status();
    if (!(seconds > 0)) return absl::InvalidArgumentError(absl::StrCat("time ", seconds, " s"));
    const double u = std::log(seconds);
    if (absl::Status s = CheckCovers(*log_curve, u, "time"); !s.ok()) return s;
    return std::exp(LogErrorAt(*log_curve, u));
}

absl::StatusOr<double> MeanRatioOverTime(const ErrorCurve& a, const ErrorCurve& b,
                                         TimeRange range) {
    absl::StatusOr<LogCurve> la = ToLog(a), lb = ToLog(b);
    if (!la.ok()) return la.status();
    if (!lb.ok()) return lb.status();
    if (!(range.from > 0) || !(range.to >= range.from)) {
        return absl::InvalidArgumentError(
            absl::StrCat("time range ", range.from, " to ", range.to, " s"));
    }
    const double u0 = std::log(range.from), u1 = std::log(range.to);
    for (const LogCurve* curve : {&*la, &*lb}) {
        for (const auto& [u, which] : {std::pair{u0, "range start"}, std::pair{u1, "range end"}}) {
            if (absl::Status s = CheckCovers(*curve, u, which); !s.ok()) return s;
        }
    }
    auto log_ratio = [&](double u) { return LogErrorAt(*lb, u) - LogErrorAt(*la, u); };
    if (u1 == u0) return std::exp(log_ratio(u0));
    // log b - log a is linear between consecutive points of either curve.
    std::vector<double> knots = {u0, u1};
    for (const LogCurve* curve : {&*la, &*lb}) {
        for (const auto& [u, e] : *curve) {
            if (u > u0 && u < u1) knots.push_back(u);
        }
    }
    std::sort(knots.begin(), knots.end());
    double integral = 0;
    for (size_t i = 1; i < knots.size(); ++i) {
        integral +=
            0.5 * (log_ratio(knots[i - 1]) + log_ratio(knots[i])) * (knots[i] - knots[i - 1]);
    }
    return std::exp(integral / (u1 - u0));
}

}  // namespace lf
