// Jobs and the results of their finished tasks in SQLite, so that a server killed at any point
// and started again on the same data folder loses nothing it acknowledged: WAL and
// synchronous=FULL, and callers acknowledge only after WaitDurable. One writer thread commits
// the queued writes in batches (group commit): one transaction and one sync for all the writes
// that queued while the previous batch was being synced.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <tuple>

#include "server/job_store.h"
#include "server/metrics.h"

struct sqlite3;

namespace lf {

class SqliteJobStore : public JobStore {
  public:
    // Opens or creates the database at `path`.
    static absl::StatusOr<std::unique_ptr<SqliteJobStore>> Open(const std::string& path);
    ~SqliteJobStore() override;  // commits what is queued

    uint64_t QueuePut(const JobRecord& job) override;
    uint64_t QueueTaskDone(const JobRecord& job, int task, std::string result) override;
    uint64_t QueueDelete(const std::string& id) override;
    absl::Status WaitDurable(uint64_t ticket) override;
    absl::StatusOr<JobRecord> Get(const std::string& id) const override;
    absl::StatusOr<std::vector<JobRecord>> List(const JobQuery& query = {}) const override;
    absl::StatusOr<std::optional<std::string>> FindRequest(
        const std::string& request_id) const override;
    absl::StatusOr<std::map<int, std::string>> TaskResults(const std::string& id) const override;

    // For /healthz: Ok while the database answers a read and the last commit succeeded.
    absl::Status Health() const;
    // Ended jobs kept (see retention), by final state.
    absl::StatusOr<std::map<JobState, int64_t>> CountEnded() const;
    // Seconds of each commit of the writer thread: a transaction of queued writes and its sync.
    const Histogram& write_seconds() const { return write_seconds_; }

  private:
    // A record to put, with the columns drawn from it; or, with `remove`, a job to delete.
    struct Write {
        std::string job_id;
        bool remove = false;
        uint64_t seq = 0;
        bool final = false;
        std::string request_id = {};
        std::optional<int64_t> finished_us = {};  // ended jobs only
        std::string record = {};                  // EncodeJobRecord
        int task = -1;                            // with a task result when >= 0
        std::string result = {};
    };
    static Write PutOf(const JobRecord& job);
    // Brings a database of an earlier version to this one's schema (see Open).
    static absl::Status Migrate(sqlite3* db);

    explicit SqliteJobStore(sqlite3* db);
    uint64_t Queue(Write write);
    void WriterLoop();
    absl::Status Commit(const std::deque<Write>& batch);  // one transaction

    mutable std::mutex db_mutex_;  // the connection: the writer's transaction or a read
    sqlite3* db_;

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
