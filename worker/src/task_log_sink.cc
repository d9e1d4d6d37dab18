#include "lf/worker/task_log_sink.h"

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "lf/core/plural.h"

namespace lf {

namespace {

thread_local bool ignored_thread = false;

}  // namespace

void TaskLog::Add(TaskLogLine line) {
    if (line.text.size() > bounds_.max_line_bytes) {
        line.text = absl::StrCat(line.text.substr(0, bounds_.max_line_bytes), "...(",
                                 line.text.size(), " bytes)");
    }
    std::lock_guard<std::mutex> lock(mutex_);
    bytes_ += line.text.size();
    lines_.push_back(std::move(line));
    while (lines_.size() > bounds_.max_lines || bytes_ > bounds_.max_bytes) {
        bytes_ -= lines_.front().text.size();
        last_dropped_ = lines_.front().time;
        ++dropped_;
        lines_.pop_front();
    }
}

std::vector<TaskLogLine> TaskLog::Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<TaskLogLine> taken;
    taken.reserve(lines_.size() + 1);
    if (dropped_ > 0) {
        TaskLogLine& note = taken.emplace_back();
        note.time = last_dropped_;
        note.level = "warning";
        note.text = absl::StrCat("... ", Plural(dropped_, "line"), " dropped");
        dropped_ = 0;
    }
    for (TaskLogLine& line : lines_) taken.push_back(std::move(line));
    lines_.clear();
    bytes_ = 0;
    return taken;
}

std::shared_ptr<TaskLogSink> TaskLogSink::Install(TaskLogBounds bounds) {
    auto sink = std::make_shared<TaskLogSink>(bounds);
    spdlog::apply_all(
        [&](const std::shared_ptr<spdlog::logger>& logger) { logger->sinks().push_back(sink); });
    // The default logger is not always registered; NamedLogger clones its sinks.
    std::vector<spdlog::sink_ptr>& defaults = spdlog::default_logger()->sinks();
    if (std::find(defaults.begin(), defaults.end(), sink) == defaults.end()) {
        defaults.push_back(sink);
    }
    return sink;
}

std::shared_ptr<TaskLog> TaskLogSink::Begin() {
    auto log = std::make_shared<TaskLog>(bounds_);
    std::lock_guard<std::mutex> lock(mutex_);
    current_ = log;
    return log;
}

void TaskLogSink::End() {
    std::lock_guard<std::mutex> lock(mutex_);
    current_.reset();
}

void TaskLogSink::IgnoreThisThread() { ignored_thread = true; }

void TaskLogSink::sink_it_(const spdlog::details::log_msg& msg) {
    if (!current_ || ignored_thread) return;
    TaskLogLine line;
    line.time = absl::FromChrono(msg.time);
    line.level = std::string(spdlog::level::to_string_view(msg.level).data(),
                             spdlog::level::to_string_view(msg.level).size());
    line.text = absl::StrCat("[", std::string(msg.logger_name.data(), msg.logger_name.size()), "] ",
                             std::string(msg.payload.data(), msg.payload.size()));
    current_->Add(std::move(line));
}

}  // namespace lf
