#include "server/http_listener.h"

#include <httplib.h>
#include <sys/socket.h>

#include <thread>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "lf/core/log.h"
#include "server/metrics.h"

namespace lf {

namespace {

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("http"); }

constexpr char kText[] = "text/plain; charset=utf-8";
// The exposition format's content type, version 0.0.4.
constexpr char kMetricsType[] = "text/plain; version=0.0.4; charset=utf-8";

HttpAnswer Unavailable(const absl::Status& why) {
    return {503, kText, absl::StrCat("not ok: ", why.message(), "\n")};
}

}  // namespace

HttpAnswer HealthzAnswer(Farm& farm) {
    if (absl::Status s = farm.store().Health(); !s.ok()) return Unavailable(s);
    return {200, kText, "ok\n"};
}

HttpAnswer MetricsAnswer(Farm& farm) {
    const absl::StatusOr<std::map<JobState, int64_t>> ended = farm.store().CountEnded();
    if (!ended.ok()) return Unavailable(ended.status());
    const SchedulerLoad load = farm.scheduler().Load();
    const SchedulerMetrics& counted = farm.scheduler().metrics();
    auto ended_in = [&](JobState state) {
        auto it = ended->find(state);
        return double(it == ended->end() ? 0 : it->second);
    };
    MetricsText text;
    text.AddGauge("lightfarm_jobs", "Jobs by state: queued and running now, ended ones kept.",
                  "state",
                  {{"queued", load.jobs_queued},
                   {"running", load.jobs_running},
                   {"succeeded", ended_in(JobState::kSucceeded)},
                   {"failed", ended_in(JobState::kFailed)},
                   {"cancelled", ended_in(JobState::kCancelled)}});
    text.AddGauge("lightfarm_tasks", "Tasks of queued and running jobs, queued or leased now.",
                  "state",
                  {{"queued", double(load.tasks_queued)}, {"running", double(load.tasks_running)}});
    text.AddGauge("lightfarm_workers",
                  "Workers heard from within a lease (live), holding a lease (busy) or not (idle).",
                  "state",
                  {{"live", load.workers_live},
                   {"busy", load.workers_busy},
                   {"idle", load.workers_live - load.workers_busy}});
    text.AddGauge("lightfarm_queue_depth", "Tasks queued and waiting for a worker.",
                  double(load.tasks_queued));
    text.AddHistogram("lightfarm_task_duration_seconds",
                      "Seconds from a task's lease to its accepted result, per completed task.",
                      counted.task_seconds.snapshot());
    text.AddCounter("lightfarm_task_failures_total",
                    "Counted task failures: expired leases, task errors, refused results.",
                    counted.task_failures.value());
    text.AddCounter("lightfarm_leases_total", "Task leases handed out to workers.",
                    counted.leases.value());
    text.AddHistogram("lightfarm_store_write_seconds",
                      "Seconds of each job store commit (one transaction and its sync).",
                      farm.store().write_seconds().snapshot());
    return {200, kMetricsType, text.text()};
}

struct HttpListener::Server {
    httplib::Server http;
    std::thread thread;
};

HttpListener::HttpListener(std::unique_ptr<Server> server, int port)
    : server_(std::move(server)), port_(port) {}

absl::StatusOr<std::unique_ptr<HttpListener>> HttpListener::Start(const std::string& host_port,
                                                                  Farm& farm) {
    const size_t colon = host_port.rfind(':');
    int port = 0;
    if (colon == std::string::npos || colon == 0 ||
        !absl::SimpleAtoi(host_port.substr(colon + 1), &port) || port < 0 || port > 65535) {
        return absl::InvalidArgumentError(
            absl::StrCat("--http ", host_port, ": expected HOST:PORT, as 127.0.0.1:9090"));
    }
    std::string host = host_port.substr(0, colon);
    if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
        host = host.substr(1, host.size() - 2);  // [::1]:9090
    }
    auto server = std::make_unique<Server>();
    // httplib sets SO_REUSEPORT, with which a second server would share the port and answer
    // scrapes at random: only SO_REUSEADDR, so that a port in use is an error.
    server->http.set_socket_options([](socket_t sock) {
        int yes = 1;
        setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    auto answer = [&farm](HttpAnswer (*handler)(Farm&)) {
        return [&farm, handler](const httplib::Request&, httplib::Response& response) {
            HttpAnswer a = handler(farm);
            response.status = a.status;
            response.set_content(std::move(a.body), a.content_type.c_str());
        };
    };
    server->http.Get("/healthz", answer(&HealthzAnswer));
    server->http.Get("/metrics", answer(&MetricsAnswer));
    const bool bound = port == 0 ? (port = server->http.bind_to_any_port(host)) > 0
                                 : server->http.bind_to_port(host, port);
    if (!bound) {
        return absl::FailedPreconditionError(absl::StrCat(
            "cannot listen on ", host_port, " for --http (is another process using the port?)"));
    }
    httplib::Server* http = &server->http;
    server->thread = std::thread([http] { http->listen_after_bind(); });
    // stop() does nothing until the loop runs: wait for it, so the destructor can end it.
    while (!server->http.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    Log()->info("serving /healthz and /metrics on {}:{}", host, port);
    return std::unique_ptr<HttpListener>(new HttpListener(std::move(server), port));
}

HttpListener::~HttpListener() {
    server_->http.stop();
    server_->thread.join();
}

}  // namespace lf
