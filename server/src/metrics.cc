#include "lf/server/metrics.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace lf {

namespace {

int64_t UnixMinute(absl::Time t) { return absl::ToUnixSeconds(t) / 60; }

}  // namespace

void MinuteCounts::Add(absl::Time now, uint64_t n) {
    const int64_t minute = UnixMinute(now);
    Bucket& b = buckets_[size_t(minute % kMinutes)];
    if (b.minute.load(std::memory_order_relaxed) != minute) {
        // Emptied before it is stamped: a reader that sees the new minute sees no old count.
        b.count.store(0, std::memory_order_relaxed);
        b.minute.store(minute, std::memory_order_release);
    }
    b.count.fetch_add(n, std::memory_order_relaxed);
}

std::vector<uint64_t> MinuteCounts::LastHour(absl::Time now) const {
    const int64_t last = UnixMinute(now);
    std::vector<uint64_t> counts;
    counts.reserve(kMinutes);
    for (int64_t minute = last - kMinutes + 1; minute <= last; ++minute) {
        const Bucket& b = buckets_[size_t(minute % kMinutes)];
        counts.push_back(b.minute.load(std::memory_order_acquire) == minute
                             ? b.count.load(std::memory_order_relaxed)
                             : 0);
    }
    return counts;
}

Histogram::Histogram(std::vector<double> upper_bounds)
    : upper_bounds_(std::move(upper_bounds)),
      buckets_(std::make_unique<std::atomic<uint64_t>[]>(upper_bounds_.size() + 1)) {}

void Histogram::Observe(double value) {
    const size_t bucket =
        size_t(std::lower_bound(upper_bounds_.begin(), upper_bounds_.end(), value) -
               upper_bounds_.begin());
    buckets_[bucket].fetch_add(1, std::memory_order_relaxed);
    sum_.fetch_add(value, std::memory_order_relaxed);
}

Histogram::Snapshot Histogram::snapshot() const {
    Snapshot s;
    s.upper_bounds = upper_bounds_;
    s.sum = sum_.load(std::memory_order_relaxed);
    uint64_t total = 0;
    for (size_t i = 0; i <= upper_bounds_.size(); ++i) {
        total += buckets_[i].load(std::memory_order_relaxed);
        s.cumulative.push_back(total);
    }
    return s;
}

std::string FormatMetricValue(double value) {
    if (std::isnan(value)) return "NaN";
    if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
    char buffer[32];
    const std::to_chars_result r = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, r.ptr);
}

void MetricsText::Family(const std::string& name, const std::string& help,
                         const std::string& type) {
    absl::StrAppend(&text_, "# HELP ", name, " ", help, "\n# TYPE ", name, " ", type, "\n");
}

void MetricsText::AddCounter(const std::string& name, const std::string& help, uint64_t value) {
    Family(name, help, "counter");
    absl::StrAppend(&text_, name, " ", value, "\n");
}

void MetricsText::AddGauge(const std::string& name, const std::string& help, double value) {
    Family(name, help, "gauge");
    absl::StrAppend(&text_, name, " ", FormatMetricValue(value), "\n");
}

void MetricsText::AddGauge(const std::string& name, const std::string& help,
                           const std::string& label,
                           const std::vector<std::pair<std::string, double>>& values) {
    Family(name, help, "gauge");
    for (const auto& [label_value, value] : values) {
        absl::StrAppend(&text_, name, "{", label, "=\"", label_value, "\"} ",
                        FormatMetricValue(value), "\n");
    }
}

void MetricsText::AddHistogram(const std::string& name, const std::string& help,
                               const Histogram::Snapshot& histogram) {
    Family(name, help, "histogram");
    for (size_t i = 0; i < histogram.cumulative.size(); ++i) {
        const std::string le = i < histogram.upper_bounds.size()
                                   ? FormatMetricValue(histogram.upper_bounds[i])
                                   : "+Inf";
        absl::StrAppend(&text_, name, "_bucket{le=\"", le, "\"} ", histogram.cumulative[i], "\n");
    }
    absl::StrAppend(&text_, name, "_sum ", FormatMetricValue(histogram.sum), "\n", name, "_count ",
                    histogram.count(), "\n");
}

}  // namespace lf
