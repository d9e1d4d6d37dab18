// Jobs as the server records them, behind a small interface: in memory or in SQLite
// (server/sqlite_job_store.h), each record in the stored form of server/job_record_codec.h. The
// scheduler keeps the live task and lease state of running jobs itself and writes the job-level
// record here on every change, and each finished task's result with it, so that a restarted
// server can rebuild its running jobs; finished jobs live only here.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/job/job_record.h"

namespace lf {

// Which jobs JobStore::List returns, newest (highest seq) first.
struct JobQuery {
    uint64_t before_seq = 0;  // only jobs submitted before this seq; 0: from the newest
    size_t limit = 0;         // at most this many; 0: all
    // Only jobs that ended before this time (retention); InfinitePast: every job.
    absl::Time ended_before = absl::InfinitePast();
    // Only the jobs of this owner (JobSpec::owner); nullopt: everyone's.
    std::optional<std::string> owner;
};

class JobStore {
  public:
    virtual ~JobStore() = default;
    // Writes are queued and become durable in the order they were queued; a store may commit
    // many at once (group commit), so that callers can wait for durability without holding
    // their locks. Each returns a ticket for WaitDurable. A record whose request id another
    // job holds is refused (AlreadyExists from WaitDurable).
    virtual uint64_t QueuePut(const JobRecord& job) = 0;  // insert or replace, by id
    // The job's record together with the encoded TileSums of its task `task` and the task's
    // history, in one write. A succeeded still's record drops the job's task results; a failed
    // or cancelled job, or a succeeded shot, keeps them for `lightfarm requeue` (--frames of a
    // shot: Scheduler::RequeueFrames) until deleted.
    virtual uint64_t QueueTaskDone(const JobRecord& job, int task, std::string result,
                                   const TaskHistory& history) = 0;
    // The job's record with the results of its tasks `tasks` removed, in one write.
    virtual uint64_t QueuePutDropping(const JobRecord& job, const std::vector<int>& tasks) = 0;
    // Removes the job's record and task results; nothing to remove is not an error.
    virtual uint64_t QueueDelete(const std::string& id) = 0;
    // Blocks until the write of `ticket`, and every one before it, is durable; or its error.
    virtual absl::Status WaitDurable(uint64_t ticket) = 0;
    absl::Status Put(const JobRecord& job) { return WaitDurable(QueuePut(job)); }
    absl::Status Delete(const std::string& id) { return WaitDurable(QueueDelete(id)); }

    // Reads see durable writes only.
    virtual absl::StatusOr<JobRecord> Get(const std::string& id) const = 0;  // NotFound
    virtual absl::StatusOr<std::vector<JobRecord>> List(const JobQuery& query = {}) const = 0;
    // The job submitted with this client request id, if any.
    virtual absl::StatusOr<std::optional<std::string>> FindRequest(
        const std::string& request_id) const = 0;
    // What QueueTaskDone recorded for a job that has not ended, by task index.
    struct RecordedTask {
        std::string result;
        TaskHistory history;  // empty for a result recorded before histories were
        // The order it was written in, among the job's results: a restart merges them again
        // in that order, the order they merged in (a shot's passes take indices as they merge).
        int64_t order = 0;
    };
    virtual absl::StatusOr<std::map<int, RecordedTask>> TaskResults(
        const std::string& id) const = 0;
};

// Nothing outlives the process, so there is nothing to recover: task results are not kept, and
// every write is "durable" at once.
class InMemoryJobStore : public JobStore {
  public:
    uint64_t QueuePut(const JobRecord& job) override;
    uint64_t QueueTaskDone(const JobRecord& job, int, std::string, const TaskHistory&) override {
        return QueuePut(job);
    }
    uint64_t QueuePutDropping(const JobRecord& job, const std::vector<int>&) override {
        return QueuePut(job);
    }
    uint64_t QueueDelete(const std::string& id) override;
    absl::Status WaitDurable(uint64_t ticket) override;
    absl::StatusOr<JobRecord> Get(const std::string& id) const override;
    absl::StatusOr<std::vector<JobRecord>> List(const JobQuery& query = {}) const override;
    absl::StatusOr<std::optional<std::string>> FindRequest(
        const std::string& request_id) const override;
    absl::StatusOr<std::map<int, RecordedTask>> TaskResults(const std::string&) const override {
        return std::map<int, RecordedTask>{};
    }

  private:
    static constexpr uint64_t kDone = 0;  // the ticket of a write that succeeded
    mutable std::mutex mutex_;
    std::map<std::string, JobRecord> jobs_;
    uint64_t last_refused_ = 0;
    std::map<uint64_t, absl::Status> refused_;  // by ticket
};

}  // namespace lf
