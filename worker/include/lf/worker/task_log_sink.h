// What a worker logs while it runs a task, captured for the coordinator (`lightfarm logs`): an
// spdlog sink on every logger of the worker (the kernels' too), which hands each line to the
// task that is running, and each task's lines held until a heartbeat or the result takes them.
#pragma once

#include <spdlog/sinks/base_sink.h>

#include <deque>
#include <memory>
#include <mutex>
#include <vector>

#include "lf/job/task_status.h"

namespace lf {

// What one task holds between two sends; the coordinator keeps its own bounds
// (server/task_log_store.h).
struct TaskLogBounds {
    size_t max_lines = 1000;
    size_t max_bytes = 256 << 10;
    size_t max_line_bytes = 4096;  // a longer line is cut
};

// One task's lines not yet sent. Past the bounds the oldest go, counted: the newest lines (the
// render's outcome, an error) are those worth sending.
class TaskLog {
  public:
    explicit TaskLog(TaskLogBounds bounds) : bounds_(bounds) {}
    void Add(TaskLogLine line);
    // The lines since the last Take, oldest first, after one "... N lines dropped" line when
    // some were.
    std::vector<TaskLogLine> Take();

  private:
    const TaskLogBounds bounds_;
    std::mutex mutex_;
    std::deque<TaskLogLine> lines_;  // guarded by mutex_, as the rest
    size_t bytes_ = 0;
    int64_t dropped_ = 0;
    absl::Time last_dropped_;
};

class TaskLogSink final : public spdlog::sinks::base_sink<std::mutex> {
  public:
    explicit TaskLogSink(TaskLogBounds bounds = {}) : bounds_(bounds) {}

    // Adds a sink to every logger registered now, and so (lf::NamedLogger clones the default
    // logger) to every logger made later. Call once, before the worker logs.
    static std::shared_ptr<TaskLogSink> Install(TaskLogBounds bounds = {});

    // From now until End, lines logged by any thread but those that called IgnoreThisThread
    // go to the returned log. One task at a time: a Begin ends the previous task's capture.
    std::shared_ptr<TaskLog> Begin();
    void End();
    // Lines of the calling thread are never captured: a thread that works for another task than
    // the running one (the worker's result sender) calls it.
    static void IgnoreThisThread();

  protected:
    void sink_it_(const spdlog::details::log_msg& msg) override;
    void flush_() override {}

  private:
    const TaskLogBounds bounds_;
    std::shared_ptr<TaskLog> current_;  // guarded by base_sink's mutex_
};

}  // namespace lf
