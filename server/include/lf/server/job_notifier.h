// lightfarm-server --notify-url: POSTs a JSON object when a job ends (succeeded, failed,
// cancelled), from its own thread: a failing or hanging endpoint never holds up the scheduler.
// The queue is bounded; beyond it the oldest notifications are dropped with a warning.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/job/job_record.h"

namespace httplib {
class Client;
}

namespace lf {

struct JobNotifierOptions {
    size_t max_queued = 1000;
    absl::Duration timeout = absl::Seconds(5);  // connect, and read of the answer, per attempt
    int attempts = 3;                           // per notification
    absl::Duration first_retry = absl::Milliseconds(500);  // doubling between attempts
};

// The body POSTed for an ended job: {"job_id","name","owner","state","error","submitted",
// "started","finished"} with RFC 3339 times ("" for a time not reached).
std::string JobEndedJson(const JobRecord& job);

class JobNotifier {
  public:
    // `url`: http:// or https://, a host and an optional port and path; InvalidArgument naming
    // --notify-url otherwise.
    static absl::StatusOr<std::unique_ptr<JobNotifier>> Start(const std::string& url,
                                                              JobNotifierOptions options = {});
    ~JobNotifier();  // aborts the attempt under way, drops the rest
    JobNotifier(const JobNotifier&) = delete;
    JobNotifier& operator=(const JobNotifier&) = delete;

    // Queues the job's notification; returns at once.
    void JobEnded(const JobRecord& job);

  private:
    JobNotifier(std::string origin, std::string path, JobNotifierOptions options);
    void Run();
    // Posts one notification, retrying; false once stopping.
    bool Post(const std::string& job_id, const std::string& body);

    const std::string origin_;  // scheme://host[:port]
    const std::string path_;
    const JobNotifierOptions options_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<std::pair<std::string, std::string>> queue_;  // (job id, body)
    bool stopping_ = false;
    httplib::Client* posting_ = nullptr;  // the attempt under way, for the destructor to stop
    std::thread thread_;
};

}  // namespace lf
