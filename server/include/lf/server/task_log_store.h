// The farm's task logs and ended jobs' task lists, in their own SQLite file (DATA_DIR/logs.db)
// with their own connection: log lines arrive with every heartbeat, and their writes never wait
// for the job store's writer nor hold the scheduler's lock. A crash may lose the last lines
// (synchronous=NORMAL): nothing in this file is acknowledged to anyone.
//
// Every line comes from a worker, so from the wire: each is made safe (lf::LogSafe), cut to
// max_line_bytes, its level one of spdlog's names; a message keeps its last
// max_lines_per_message lines. Each task keeps its most recent max_lines_per_task lines and
// max_bytes_per_task bytes of text; older ones are deleted and counted in one
// "... N earlier lines dropped" line that takes the place of the first ones dropped.
#pragma once

#include <sqlite3.h>

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/job/task_status.h"

namespace lf {

struct TaskLogLimits {
    int max_lines_per_task = 1000;
    int64_t max_bytes_per_task = 256 << 10;
    size_t max_line_bytes = 4096;
    int max_lines_per_message = 1000;
};

class TaskLogStore {
  public:
    static absl::StatusOr<std::unique_ptr<TaskLogStore>> Open(const std::string& path,
                                                              TaskLogLimits limits = {});
    ~TaskLogStore();
    TaskLogStore(const TaskLogStore&) = delete;
    TaskLogStore& operator=(const TaskLogStore&) = delete;

    // Appends lines a worker logged during attempt `attempt` of the job's task `task` (their
    // time, level and text; the rest is set here), then trims the task to the limits.
    absl::Status Append(const std::string& job_id, int task, int attempt, const std::string& worker,
                        std::vector<TaskLogLine> lines);
    // At most `max_lines` of the job's lines after `after_seq` (only task `task`'s when set), in
    // seq order; next_seq is the last one's seq (after_seq when there is none). job_ended is left
    // false: the store does not know.
    absl::StatusOr<TaskLogPage> Read(const std::string& job_id, std::optional<int> task,
                                     int64_t after_seq, int max_lines);
    // The lines kept per task of the job, the "dropped" line included.
    absl::StatusOr<std::map<int, int>> LineCounts(const std::string& job_id);

    // An ended job's tasks as the scheduler last held them (Scheduler::OnTasksEnded).
    absl::Status RecordTasks(const std::string& job_id, const std::vector<TaskStatus>& tasks);
    // What RecordTasks kept, by index; empty for a job with none recorded.
    absl::StatusOr<std::vector<TaskStatus>> Tasks(const std::string& job_id);

    // Removes the jobs' lines and tasks.
    absl::Status Delete(const std::vector<std::string>& job_ids);

    const TaskLogLimits& limits() const { return limits_; }

  private:
    TaskLogStore(sqlite3* db, TaskLogLimits limits) : db_(db), limits_(limits) {}
    // Deletes the task's oldest lines beyond the limits; returns how many.
    absl::StatusOr<int64_t> Trim(const std::string& job_id, int task);
    // Counts `dropped` more lines in the task's "dropped" line, adding it at `seq` (the place
    // of the newest line it stands for, so before every line kept) when there is none yet.
    absl::Status CountDropped(const std::string& job_id, int task, int64_t dropped,
                              std::optional<int64_t> seq, const TaskLogLine& like);

    std::mutex mutex_;  // one connection, used by one thread at a time
    sqlite3* db_;
    const TaskLogLimits limits_;
};

}  // namespace lf
