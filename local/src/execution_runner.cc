#include "lf/local/execution_runner.h"

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <condition_variable>
#include <deque>
#include <mutex>
#include <queue>
#include <set>
#include <thread>
#include <utility>
#include <vector>

namespace lf {

namespace {

class Runner {
  public:
    Runner(JobExecution& execution, const RunTask& run, const RunOptions& options,
           absl::Time started, int threads)
        : execution_(execution),
          run_(run),
          options_(options),
          clock_(options.clock ? options.clock : [] { return absl::Now(); }),
          started_(started),
          threads_(threads) {}

    absl::Status Run(tbb::task_arena& arena) {
        std::thread timer, interrupt;
        if (const std::optional<absl::Duration> limit = execution_.time_limit()) {
            timer = std::thread([this, limit] { WatchTimeLimit(*limit); });
        }
        if (options_.interrupt) interrupt = std::thread([this] { WatchInterrupt(); });
        arena.execute([&] {
            {
                std::lock_guard<std::mutex> lock(mutex_);
                Queue(execution_.Start());
                Pump();
            }
            group_.wait();
        });
        {
            std::lock_guard<std::mutex> lock(mutex_);
            finished_ = true;
            changed_.notify_all();
        }
        if (timer.joinable()) timer.join();
        if (interrupt.joinable()) interrupt.join();
        return status_;
    }

  private:
    // Under the lock.
    void Queue(const std::vector<int>& tasks) {
        while (cancel_.size() < execution_.task_count()) cancel_.emplace_back(false);
        for (int t : tasks) queue_.emplace(execution_.QueueRank(t), t);
    }

    // Starts workers while fewer than `threads_` run and queued tasks wait for one. Under the
    // lock.
    void Pump() {
        while (running_ < threads_ && queue_.size() > starting_ && status_.ok() && !interrupted_) {
            ++running_;
            ++starting_;
            group_.run([this] { RunNext(); });
        }
    }

    // Runs the best task queued when it starts, not when it was spawned: TBB may run spawned
    // work in any order.
    void RunNext() {
        std::unique_lock<std::mutex> lock(mutex_);
        --starting_;
        while (!queue_.empty() && dropped_.count(queue_.top().second)) queue_.pop();
        if (!queue_.empty() && status_.ok() && !interrupted_) {
            const int t = queue_.top().second;
            queue_.pop();
            TaskAssignment lease;
            execution_.Lease(t, "", lease);
            const std::atomic<bool>& cancel = cancel_[size_t(t)];
            under_way_.insert(t);
            lock.unlock();
            const absl::Status status =
                run_(lease, cancel, [&](const TaskResult& result) { return Merge(t, result); });
            lock.lock();
            under_way_.erase(t);
            status_.Update(status);
        }
        --running_;
        Pump();
    }

    absl::Status Merge(int t, const TaskResult& result) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (dropped_.count(t)) return absl::OkStatus();  // cut short: the time limit dropped it
        absl::StatusOr<JobExecution::Merged> merged = execution_.Merge(t, result);
        if (!merged.ok()) return merged.status();
        if (!merged->job_error.ok()) return merged->job_error;
        Queue(merged->appended);
        if (options_.merged) options_.merged();
        EnforceTimeLimit(clock_());
        changed_.notify_all();
        return absl::OkStatus();
    }

    // Under the lock; true once the time limit has passed.
    bool EnforceTimeLimit(absl::Time now) {
        const std::optional<std::vector<int>> dropped = execution_.EnforceTimeLimit(started_, now);
        if (!dropped) return false;
        for (int t : *dropped) {
            dropped_.insert(t);
            cancel_[size_t(t)] = true;
        }
        return true;
    }

    // Until the run ends or *options_.interrupt is set: then the tasks under way are cut and
    // dropped, as the time limit drops them, and nothing starts any more.
    void WatchInterrupt() {
        std::unique_lock<std::mutex> lock(mutex_);
        while (!finished_) {
            if (options_.interrupt->load()) {
                interrupted_ = true;
                for (int t : under_way_) {
                    dropped_.insert(t);
                    cancel_[size_t(t)] = true;
                }
                return;
            }
            changed_.wait_for(lock, std::chrono::milliseconds(50));
        }
    }

    // Until the run ends or the limit passes, by the clock; merges wake it to look again.
    void WatchTimeLimit(absl::Duration limit) {
        std::unique_lock<std::mutex> lock(mutex_);
        while (!finished_) {
            const absl::Time now = clock_();
            if (now - started_ >= limit) {
                EnforceTimeLimit(now);
                return;
            }
            changed_.wait_for(lock, absl::ToChronoNanoseconds(started_ + limit - now) +
                                        std::chrono::milliseconds(1));
        }
    }

    JobExecution& execution_;
    const RunTask& run_;
    const RunOptions& options_;
    const RunClock clock_;
    const absl::Time started_;
    const int threads_;

    std::mutex mutex_;
    std::condition_variable changed_;
    // Queued tasks, least rank then index first.
    std::priority_queue<std::pair<uint64_t, int>, std::vector<std::pair<uint64_t, int>>,
                        std::greater<>>
        queue_;
    std::deque<std::atomic<bool>> cancel_;  // by task; a deque keeps them in place as it grows
    std::set<int> dropped_;
    std::set<int> under_way_;  // leased and not returned
    bool interrupted_ = false;
    int running_ = 0;      // workers spawned and not done
    size_t starting_ = 0;  // of them, those that have not taken a task yet
    bool finished_ = false;
    absl::Status status_;
    tbb::task_group group_;
};

}  // namespace

absl::Status RunExecution(JobExecution& execution, const RunTask& run, const RunOptions& options,
                          absl::Time started) {
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
    arena.initialize();
    Runner runner(execution, run, options, started, arena.max_concurrency());
    return runner.Run(arena);
}

}  // namespace lf
