#include "lf/server/job_notifier.h"

#include <httplib.h>

#include <nlohmann/json.hpp>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "lf/core/log.h"

namespace lf {

namespace {

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("notify"); }

std::string Rfc3339(absl::Time t) {
    if (t == absl::InfinitePast()) return "";
    return absl::FormatTime("%Y-%m-%dT%H:%M:%SZ", t, absl::UTCTimeZone());
}

}  // namespace

std::string JobEndedJson(const JobRecord& job) {
    return nlohmann::json{{"job_id", job.id},
                          {"name", job.spec.name},
                          {"owner", job.spec.owner},
                          {"state", JobStateName(job.state)},
                          {"error", job.error},
                          {"submitted", Rfc3339(job.submitted)},
                          {"started", Rfc3339(job.started)},
                          {"finished", Rfc3339(job.finished)}}
        .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

absl::StatusOr<std::unique_ptr<JobNotifier>> JobNotifier::Start(const std::string& url,
                                                                JobNotifierOptions options) {
    const bool http = absl::StartsWith(url, "http://"), https = absl::StartsWith(url, "https://");
    const size_t host_at = http ? 7 : 8;
    const size_t path_at = url.find('/', host_at);
    if ((!http && !https) || url.size() == host_at || path_at == host_at ||
        url.find_first_of(" \t\r\n") != std::string::npos) {
        return absl::InvalidArgumentError(
            absl::StrCat("--notify-url ", LogSafe(url, 256),
                         ": expected http://HOST[:PORT][/PATH] or https://"));
    }
    std::string origin = url.substr(0, path_at);
    std::string path = path_at == std::string::npos ? "/" : url.substr(path_at);
    return std::unique_ptr<JobNotifier>(
        new JobNotifier(std::move(origin), std::move(path), options));
}

JobNotifier::JobNotifier(std::string origin, std::string path, JobNotifierOptions options)
    : origin_(std::move(origin)), path_(std::move(path)), options_(options) {
    thread_ = std::thread([this] { Run(); });
}

JobNotifier::~JobNotifier() {
    {
        std::unique_lock<std::mutex> lock(mutex_);
        stopping_ = true;
        wake_.notify_all();
        // An endpoint that trickles its answer would otherwise hold the shutdown for as long as
        // it likes: stop() shuts the socket under the attempt (httplib's cross-thread abort).
        // Again until the attempt returns: one stopped before its socket opened goes on.
        while (posting_) {
            posting_->stop();
            wake_.wait_for(lock, std::chrono::milliseconds(50));
        }
    }
    thread_.join();
}

void JobNotifier::JobEnded(const JobRecord& job) {
    std::string body = JobEndedJson(job);
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (queue_.size() >= options_.max_queued) {
            Log()->warn("notify: {} notifications queued for {}: job={}'s dropped",
                        options_.max_queued, origin_, queue_.front().first);
            queue_.pop_front();
        }
        queue_.emplace_back(job.id, std::move(body));
    }
    wake_.notify_all();
}

void JobNotifier::Run() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
        wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
        if (stopping_) return;
        auto [job_id, body] = std::move(queue_.front());
        queue_.pop_front();
        lock.unlock();
        const bool going_on = Post(job_id, body);
        lock.lock();
        if (!going_on) return;
    }
}

bool JobNotifier::Post(const std::string& job_id, const std::string& body) {
    httplib::Client client(origin_);
    const int64_t timeout_us = absl::ToInt64Microseconds(options_.timeout);
    client.set_connection_timeout(0, timeout_us);
    client.set_read_timeout(0, timeout_us);
    client.set_write_timeout(0, timeout_us);
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (stopping_) return false;
        posting_ = &client;
    }
    absl::Cleanup done = [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        posting_ = nullptr;
        wake_.notify_all();
    };
    httplib::Request request;
    request.method = "POST";
    request.path = path_;
    request.body = body;
    request.set_header("Content-Type", "application/json");
    // The status is all we need: an answer's body is never read, however long or slow (httplib
    // calls the handler only for an answer with a body; a 204 comes back whole).
    int status = 0;
    request.response_handler = [&](const httplib::Response& answer) {
        status = answer.status;
        return false;
    };
    absl::Duration wait = options_.first_retry;
    std::string why;
    for (int attempt = 1; attempt <= options_.attempts; ++attempt) {
        status = 0;
        const httplib::Result answer = client.send(request);
        if (answer) status = answer->status;
        if (status >= 200 && status < 300) return true;
        why = status ? absl::StrCat("HTTP ", status) : httplib::to_string(answer.error());
        std::unique_lock<std::mutex> lock(mutex_);
        if (stopping_) return false;
        if (attempt == options_.attempts) break;
        if (wake_.wait_for(lock, absl::ToChronoMilliseconds(wait), [&] { return stopping_; })) {
            return false;
        }
        wait *= 2;
    }
    Log()->warn("notify: job={} not notified to {}{} after {} attempts: {}", job_id, origin_,
                LogSafe(path_, 256), options_.attempts, why);
    return true;
}

}  // namespace lf
