// Metric types for the server's /metrics, and their Prometheus text exposition (format 0.0.4).
// Counters and histograms are updated on the scheduler's and the store's hot paths, so an update
// is a few relaxed atomic adds and never takes a lock; gauges are not kept here but read from
// their owners (the scheduler, the store) when the text is made.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/time/time.h"

namespace lf {

class Counter {
  public:
    void Add(uint64_t n = 1) { value_.fetch_add(n, std::memory_order_relaxed); }
    uint64_t value() const { return value_.load(std::memory_order_relaxed); }

  private:
    std::atomic<uint64_t> value_{0};
};

// Observations counted in fixed buckets, each bucket holding the values at most its upper bound
// (Prometheus' `le`), plus the sum of all values.
class Histogram {
  public:
    // `upper_bounds`: finite and ascending; the +Inf bucket is implicit.
    explicit Histogram(std::vector<double> upper_bounds);

    void Observe(double value);

    struct Snapshot {
        std::vector<double> upper_bounds;
        std::vector<uint64_t> cumulative;  // per upper bound, then +Inf (= count)
        double sum = 0;
        uint64_t count() const { return cumulative.back(); }
    };
    // Read while observations go on, a snapshot may have an observation in its buckets but not
    // yet in its sum; its buckets and count always agree.
    Snapshot snapshot() const;

  private:
    const std::vector<double> upper_bounds_;
    std::unique_ptr<std::atomic<uint64_t>[]> buckets_;  // not cumulative; the last is +Inf
    std::atomic<double> sum_{0};
};

// Counts per wall-clock minute over the last hour, for the dashboard's throughput chart: a ring
// of one bucket per minute, reused an hour later. Adds come from one thread at a time (the
// scheduler's lock serializes them); reads from any thread, without a lock.
class MinuteCounts {
  public:
    static constexpr int kMinutes = 60;
    void Add(absl::Time now, uint64_t n);
    // The kMinutes minutes up to and including the one of `now`, oldest first.
    std::vector<uint64_t> LastHour(absl::Time now) const;

  private:
    struct Bucket {
        std::atomic<int64_t> minute{-1};  // since the Unix epoch
        std::atomic<uint64_t> count{0};
    };
    std::array<Bucket, kMinutes> buckets_;
};

// Builds the exposition text, one metric family (HELP, TYPE, samples) per call.
class MetricsText {
  public:
    void AddCounter(const std::string& name, const std::string& help, uint64_t value);
    void AddGauge(const std::string& name, const std::string& help, double value);
    // One sample per (label value, value): `name{label="value"} value`.
    void AddGauge(const std::string& name, const std::string& help, const std::string& label,
                  const std::vector<std::pair<std::string, double>>& values);
    void AddHistogram(const std::string& name, const std::string& help,
                      const Histogram::Snapshot& histogram);

    const std::string& text() const { return text_; }

  private:
    void Family(const std::string& name, const std::string& help, const std::string& type);
    std::string text_;
};

// A number as the exposition format writes it: the shortest text that reads back the same
// double, and +Inf, -Inf, NaN.
std::string FormatMetricValue(double value);

}  // namespace lf
