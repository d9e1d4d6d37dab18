// Scheduler capacity: simulated workers (threads, no rendering) lease tasks and complete them
// with precomputed results, against the SQLite job store with its durability on, for a few
// seconds per worker count. Prints task leases and completions per second.
//
//   build/bin/scheduler_bench [--workers 10,100,1000] [--seconds 3] [--dir DIR]
//   build/bin/scheduler_bench --recovery-jobs 200   # restart to first lease with 200 jobs
//   build/bin/scheduler_bench --made-up-workers 100000  # lease latency after that many ids
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "lf/server/scheduler.h"
#include "lf/server/sqlite_job_store.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

// Big jobs of tiny tiles: many tasks, little merging, so the scheduler and store dominate.
lf::JobSpec Spec() {
    lf::JobSpec spec;
    spec.name = "bench";
    spec.plan = {256, 256, 1, 4, 1};  // 4096 tasks of 4x4 pixels
    return spec;
}

lf::TileSums Result(const lf::TaskAssignment& lease) {
    lf::TileSums sums(lease.task.rect);
    for (lf::PixelSums& p : sums.pixels) {
        for (uint64_t s = lease.task.sample_begin; s < lease.task.sample_end; ++s) {
            p.Add(s, lf::Rgb(0.5f));
        }
    }
    return sums;
}

std::unique_ptr<lf::SqliteJobStore> OpenStore(const fs::path& dir) {
    absl::StatusOr<std::unique_ptr<lf::SqliteJobStore>> store =
        lf::SqliteJobStore::Open((dir / "jobs.db").string());
    if (!store.ok()) {
        std::fprintf(stderr, "scheduler_bench: %s\n",
                     std::string(store.status().message()).c_str());
        std::exit(1);
    }
    return std::move(*store);
}

void Capacity(const fs::path& dir, int workers, double seconds) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::unique_ptr<lf::SqliteJobStore> store = OpenStore(dir);
    lf::Scheduler scheduler({}, *store);
    for (int i = 0; i < 32; ++i) (void)scheduler.Submit(Spec());  // 131072 tasks
    std::atomic<bool> stop{false};
    std::atomic<int> finished{0};
    std::atomic<uint64_t> leases{0}, completions{0};
    std::vector<std::thread> threads;
    const auto start = Clock::now();
    for (int w = 0; w < workers; ++w) {
        threads.emplace_back([&, w] {
            const std::string name = "w" + std::to_string(w);
            while (!stop) {
                std::optional<lf::TaskAssignment> lease = scheduler.LeaseTask(name);
                if (!lease) break;
                ++leases;
                if (scheduler.Complete(lease->lease_id, name, Result(*lease)).ok()) ++completions;
            }
            ++finished;  // out of tasks
        });
    }
    const auto end = start + std::chrono::duration<double>(seconds);
    while (Clock::now() < end && finished < workers) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    stop = true;
    for (std::thread& t : threads) t.join();
    std::printf("%5d workers: %8.0f leases/s, %8.0f completions/s (%llu tasks in %.1f s)\n",
                workers, double(leases) / elapsed, double(completions) / elapsed,
                (unsigned long long)completions.load(), elapsed);
}

void Recovery(const fs::path& dir, int jobs) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    {
        std::unique_ptr<lf::SqliteJobStore> store = OpenStore(dir);
        lf::Scheduler scheduler({}, *store);
        lf::JobSpec spec = Spec();
        spec.plan = {64, 64, 4, 8, 2};  // 128 tasks
        for (int i = 0; i < jobs; ++i) {
            const std::string id = *scheduler.Submit(spec);
            // Half of each job done, so recovery merges results back too.
            for (int t = 0; t < 64; ++t) {
                std::optional<lf::TaskAssignment> lease = scheduler.LeaseTask("w");
                if (!lease || !scheduler.Complete(lease->lease_id, "w", Result(*lease)).ok()) {
                    std::fprintf(stderr, "scheduler_bench: job %s: no lease\n", id.c_str());
                    std::exit(1);
                }
            }
        }
    }
    const auto start = Clock::now();
    std::unique_ptr<lf::SqliteJobStore> store = OpenStore(dir);
    lf::Scheduler scheduler({}, *store);
    if (!scheduler.Recover().ok()) std::exit(1);
    const bool leased = scheduler.LeaseTask("w").has_value();
    std::printf("recovery of %d jobs (64 of 128 tasks done each): %.0f ms to the first lease%s\n",
                jobs, std::chrono::duration<double, std::milli>(Clock::now() - start).count(),
                leased ? "" : " (no lease!)");
}

// One worker's lease latency after `made_up` worker ids asked for work once, as a hostile client
// would, and then fell silent for longer than a lease.
void MadeUpWorkers(const fs::path& dir, int made_up) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::unique_ptr<lf::SqliteJobStore> store = OpenStore(dir);
    const lf::SchedulerOptions options;
    absl::Duration offset = absl::ZeroDuration();
    lf::Scheduler scheduler(options, *store, [&offset] { return absl::Now() + offset; });
    for (int i = 0; i < made_up; ++i) (void)scheduler.LeaseTask("made-up-" + std::to_string(i));
    (void)scheduler.Submit(Spec());
    offset = options.lease + absl::Seconds(1);
    constexpr int kLeases = 2000;
    double lease_ms = 0;
    for (int i = 0; i < kLeases; ++i) {
        const auto start = Clock::now();
        std::optional<lf::TaskAssignment> lease = scheduler.LeaseTask("w");
        lease_ms += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        if (!lease) {
            std::fprintf(stderr, "scheduler_bench: no lease\n");
            std::exit(1);
        }
    }
    std::printf("%d made-up worker ids, silent past the lease: %.4f ms per lease (mean of %d)\n",
                made_up, lease_ms / kLeases, kLeases);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"scheduler_bench: scheduler capacity and recovery time (see docs/farm.md)."};
    std::vector<int> workers = {10, 100, 1000};
    double seconds = 3;
    int recovery_jobs = 0;
    int made_up_workers = -1;
    std::string dir = (fs::temp_directory_path() / ("lf_sched_bench_" + std::to_string(getpid())));
    app.add_option("--workers", workers, "simulated worker counts")->delimiter(',');
    app.add_option("--seconds", seconds, "per worker count")->capture_default_str();
    app.add_option("--recovery-jobs", recovery_jobs, "measure the recovery time instead");
    app.add_option("--made-up-workers", made_up_workers,
                   "measure one worker's lease latency after this many made-up worker ids");
    app.add_option("--dir", dir, "folder for the store (a real disk)")->capture_default_str();
    CLI11_PARSE(app, argc, argv);
    spdlog::set_level(spdlog::level::warn);
    if (recovery_jobs > 0) {
        Recovery(dir, recovery_jobs);
    } else if (made_up_workers >= 0) {
        MadeUpWorkers(dir, made_up_workers);
    } else {
        for (int n : workers) Capacity(dir, n, seconds);
    }
    fs::remove_all(dir);
    return 0;
}
