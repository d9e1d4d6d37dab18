// Jobs and the results of their finished tasks in SQLite, so that a server killed at any point
// and started again on the same data folder loses nothing it acknowledged: WAL and
// synchronous=FULL, and callers acknowledge only after WaitDurable. One writer thread commits
// the queued writes in batches (group commit): one transaction and one sync for all the writes
// that queued while the previous batch was being synced.
//
// Beside the jobs, an append-only history of ended work (issue 30, `lightfarm stats`): a row a
// merged task (task_stats) and a row an ended job (job_stats) with its workers' failures
// (worker_failure_stats), written in the same transactions as the records, kept when a job is
// deleted, and pruned after kStatsKeptFor.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <unordered_map>

#include "lf/job/farm_stats.h"
#include "lf/server/job_store.h"
#include "lf/server/metrics.h"

struct sqlite3;

namespace lf {

class SqliteJobStore : public JobStore {
  public:
    // Opens or creates the database at `path`.
    static absl::StatusOr<std::unique_ptr<SqliteJobStore>> Open(const std::string& path);
    ~SqliteJobStore() override;  // commits what is queued

    uint64_t QueuePut(const JobRecord& job) override;
    uint64_t QueueTaskDone(const JobRecord& job, int task, std::string result,
                           const TaskHistory& history) override;
    uint64_t QueuePutDropping(const JobRecord& job, const std::vector<int>& tasks) override;
    uint64_t QueueDelete(const std::string& id) override;
    absl::Status WaitDurable(uint64_t ticket) override;
    absl::StatusOr<JobRecord> Get(const std::string& id) const override;
    absl::StatusOr<std::vector<JobRecord>> List(const JobQuery& query = {}) const override;
    absl::StatusOr<std::optional<std::string>> FindRequest(
        const std::string& request_id) const override;
    absl::StatusOr<std::map<int, RecordedTask>> TaskResults(const std::string& id) const override;

    // For /healthz: Ok while the database answers a read and the last commit succeeded.
    absl::Status Health() const;
    // Ended jobs kept (see retention), by final state.
    absl::StatusOr<std::map<JobState, int64_t>> CountEnded() const;
    // The history since query.since, summed in SQL (however long the history, the rows read are
    // one per owner, state and worker).
    absl::StatusOr<FarmStats> Stats(const StatsQuery& query) const;
    static constexpr absl::Duration kStatsKeptFor = absl::Hours(400 * 24);
    // Seconds of each commit of the writer thread: a transaction of queued writes and its sync.
    const Histogram& write_seconds() const { return write_seconds_; }

  private:
    // A record to put, with the columns drawn from it; or, with `remove`, a job to delete.
    struct Write {
        std::string job_id;
        bool remove = false;
        uint64_t seq = 0;
        bool final = false;
        // A succeeded still: its task results go. A failed or cancelled job, or a succeeded
        // shot, keeps them (requeue, requeue --frames).
        bool drop_results = false;
        std::vector<int> drop_tasks = {};  // task results to remove with the record
        std::string request_id = {};
        std::optional<int64_t> finished_us = {};  // ended jobs only
        std::string record = {};                  // EncodeJobRecord
        int task = -1;                            // with a task result when >= 0
        std::string result = {};
        std::string history = {};  // EncodeTaskHistory, with the result
        // For the history tables: the job's owner, a done task's history, an ended job's state
        // and its workers' failures.
        std::string owner = {};
        TaskHistory done = {};
        JobState state = JobState::kQueued;
        std::vector<WorkerFailures> worker_failures = {};
    };
    // The history rows of a task's result, and of an ended job's record (in Commit's
    // transaction; a job's end also prunes the history).
    absl::Status RecordTaskStats(const Write& w);
    absl::Status RecordJobEnd(const Write& w);
    static Write PutOf(const JobRecord& job);
    // Brings a database of an earlier `version` to this one's schema (see Open).
    static absl::Status Migrate(sqlite3* db, int64_t version);

    explicit SqliteJobStore(sqlite3* db);
    uint64_t Queue(Write write);
    void WriterLoop();
    absl::Status Commit(const std::deque<Write>& batch);  // one transaction

    std::mutex db_mutex_;  // the writer's connection: its transactions, and Open's setup
    sqlite3* db_;
    // Reads go through a connection of their own: under WAL they see the last commit without
    // waiting for the writer's transaction and sync, and a long read (a dashboard's job list)
    // never holds up a commit that a task's result waits for.
    mutable std::mutex read_mutex_;
    sqlite3* read_db_ = nullptr;
    // Decoded records by id with a hash of their stored text (under read_mutex_): lists of the
    // same jobs, polled by dashboards, parse each record's JSON once, not on every poll. A
    // record whose text changed is decoded again; the cache is emptied when it reaches
    // kDecodedCacheSize.
    static constexpr size_t kDecodedCacheSize = 20000;
    mutable std::unordered_map<std::string, std::pair<size_t, JobRecord>> decoded_;
    absl::StatusOr<JobRecord> DecodeCached(std::string_view id, std::string_view record) const;

    mutable std::mutex queue_mutex_;
    std::condition_variable queued_cv_, durable_cv_;
    std::deque<Write> queue_;
    uint64_t last_ticket_ = 0, durable_ = 0;  // tickets issued; committed (or failed) through
    std::vector<std::tuple<uint64_t, uint64_t, absl::Status>> failed_;  // (first, last, error)
    bool stop_ = false;
    absl::Status last_commit_;  // under queue_mutex_
    Histogram write_seconds_{
        {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10}};
    std::thread writer_;  // last: it starts in the constructor and uses the members above
};

}  // namespace lf
