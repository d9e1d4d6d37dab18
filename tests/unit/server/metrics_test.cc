// The metric types and their Prometheus text: the exact exposition of known values, bucket
// edges (a value equal to a bound counts in that bound's bucket), and no update lost when many
// threads count at once.
#include "lf/server/metrics.h"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace lf {
namespace {

TEST(Metrics, ExpositionOfKnownValuesIsExact) {
    Counter leases;
    leases.Add();
    leases.Add(41);
    Histogram seconds({0.5, 1, 2.5});
    for (double v : {0.25, 0.5, 0.75, 2.5, 100.0}) seconds.Observe(v);
    MetricsText text;
    text.AddCounter("lightfarm_leases_total", "Leases.", leases.value());
    text.AddGauge("lightfarm_queue_depth", "Queued.", 7);
    text.AddGauge("lightfarm_workers", "Workers.", "state", {{"live", 3}, {"busy", 1}});
    text.AddHistogram("lightfarm_task_duration_seconds", "Task seconds.", seconds.snapshot());
    EXPECT_EQ(text.text(),
              "# HELP lightfarm_leases_total Leases.\n"
              "# TYPE lightfarm_leases_total counter\n"
              "lightfarm_leases_total 42\n"
              "# HELP lightfarm_queue_depth Queued.\n"
              "# TYPE lightfarm_queue_depth gauge\n"
              "lightfarm_queue_depth 7\n"
              "# HELP lightfarm_workers Workers.\n"
              "# TYPE lightfarm_workers gauge\n"
              "lightfarm_workers{state=\"live\"} 3\n"
              "lightfarm_workers{state=\"busy\"} 1\n"
              "# HELP lightfarm_task_duration_seconds Task seconds.\n"
              "# TYPE lightfarm_task_duration_seconds histogram\n"
              "lightfarm_task_duration_seconds_bucket{le=\"0.5\"} 2\n"
              "lightfarm_task_duration_seconds_bucket{le=\"1\"} 3\n"
              "lightfarm_task_duration_seconds_bucket{le=\"2.5\"} 4\n"
              "lightfarm_task_duration_seconds_bucket{le=\"+Inf\"} 5\n"
              "lightfarm_task_duration_seconds_sum 104\n"
              "lightfarm_task_duration_seconds_count 5\n");
}

TEST(Metrics, EmptyHistogramHasEveryBucketAtZero) {
    MetricsText text;
    text.AddHistogram("h", "H.", Histogram({0.001}).snapshot());
    EXPECT_EQ(text.text(),
              "# HELP h H.\n# TYPE h histogram\nh_bucket{le=\"0.001\"} 0\n"
              "h_bucket{le=\"+Inf\"} 0\nh_sum 0\nh_count 0\n");
}

TEST(Metrics, ValuesAreWrittenToReadBackExactly) {
    EXPECT_EQ(FormatMetricValue(0.1), "0.1");
    EXPECT_EQ(FormatMetricValue(1e-9), "1e-09");
    EXPECT_EQ(FormatMetricValue(123456789012.0), "123456789012");
    EXPECT_EQ(FormatMetricValue(1.0 / 0.0), "+Inf");
    EXPECT_EQ(FormatMetricValue(-1.0 / 0.0), "-Inf");
    EXPECT_EQ(FormatMetricValue(0.0 / 0.0), "NaN");
}

TEST(Metrics, ConcurrentUpdatesAreAllCounted) {
    Counter counter;
    Histogram histogram({1, 2});
    constexpr int kThreads = 4, kEach = 100'000;
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
        threads.emplace_back([&, t] {
            for (int i = 0; i < kEach; ++i) {
                counter.Add();
                histogram.Observe(double(t % 3));  // 0, 1, 2, 0: whole numbers sum exactly
            }
        });
    }
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(counter.value(), uint64_t(kThreads * kEach));
    const Histogram::Snapshot s = histogram.snapshot();
    EXPECT_EQ(s.cumulative, (std::vector<uint64_t>{3 * kEach, 4 * kEach, 4 * kEach}));
    EXPECT_EQ(s.sum, double(3 * kEach));
}

}  // namespace
}  // namespace lf
