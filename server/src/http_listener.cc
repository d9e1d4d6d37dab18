#include "lf/server/http_listener.h"

#include <httplib.h>
#include <sys/socket.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <memory>
#include <thread>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "http_gate.h"
#include "lf/core/log.h"
#include "lf/server/dashboard.h"
#include "lf/server/metrics.h"

namespace lf {

namespace {

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("http"); }

constexpr char kText[] = "text/plain; charset=utf-8";
// The exposition format's content type, version 0.0.4.
constexpr char kMetricsType[] = "text/plain; version=0.0.4; charset=utf-8";

// The dashboard's requests are small: a token, a priority.
constexpr size_t kMaxBodyBytes = 64 << 10;
// A downloaded file goes out in pieces of this size.
constexpr size_t kFileChunkBytes = 256 << 10;

HttpRequest FromHttplib(const httplib::Request& r) {
    HttpRequest request{r.method, r.path, {}, {}, r.body, r.remote_addr};
    for (const auto& [name, value] : r.params) request.query.emplace(name, value);
    for (const auto& [name, value] : r.headers) {
        std::string lower = name;
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        request.headers.emplace(std::move(lower), value);
    }
    return request;
}

// A file answer: opened now (a file replaced or removed later is still read whole), sent in
// pieces of kFileChunkBytes.
void ReplyWithFile(const HttpAnswer& a, httplib::Response& response) {
    auto in = std::make_shared<std::ifstream>(a.file, std::ios::binary | std::ios::ate);
    if (!*in) {
        Log()->error("cannot open {} to send it", a.file);
        response.status = 500;
        response.set_content("the file cannot be read on the server\n", kText);
        return;
    }
    const size_t size = size_t(in->tellg());
    in->seekg(0);
    response.set_content_provider(
        size, a.content_type, [in](size_t offset, size_t length, httplib::DataSink& sink) {
            std::vector<char> piece(std::min(length, kFileChunkBytes));
            in->seekg(std::streamoff(offset));
            in->read(piece.data(), std::streamsize(piece.size()));
            return in->gcount() > 0 && sink.write(piece.data(), size_t(in->gcount()));
        });
}

void Reply(HttpAnswer a, httplib::Response& response) {
    response.status = a.status;
    for (auto& [name, value] : a.headers) response.set_header(name, value);
    if (a.status == 304) return;
    if (!a.file.empty()) return ReplyWithFile(a, response);
    response.set_content(std::move(a.body), a.content_type.c_str());
}

HttpAnswer Unavailable(const absl::Status& why) {
    return {503, kText, absl::StrCat("not ok: ", why.message(), "\n")};
}

HttpAnswer BodyTooLarge() {
    return {413, kText, absl::StrCat("request body over ", kMaxBodyBytes, " bytes\n")};
}

// 413 and 408 for the requests the gate cut off; httplib would answer 400.
httplib::Server::HandlerResponse CutOff(const httplib::Request&, httplib::Response& response) {
    if (HttpGate::BodyOverLimit()) {
        Reply(BodyTooLarge(), response);
    } else if (HttpGate::ReadTimedOut()) {
        response.status = 408;
        response.set_content("request not received in time\n", kText);
    } else {
        return httplib::Server::HandlerResponse::Unhandled;
    }
    response.set_header("Connection", "close");
    return httplib::Server::HandlerResponse::Handled;
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
    std::unique_ptr<httplib::Server> http;  // a GatedServer, of httplib::SSLServer under TLS
    HttpGate* gate = nullptr;
    std::unique_ptr<Dashboard> dashboard;
    std::thread thread;
};

HttpListener::HttpListener(std::unique_ptr<Server> server, int port)
    : server_(std::move(server)), port_(port) {}

absl::StatusOr<std::unique_ptr<HttpListener>> HttpListener::Start(
    const std::string& host_port, Farm& farm, const HttpListenerOptions& options) {
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
    const bool tls = !options.tls_cert.empty() && !options.tls_key.empty();
    HttpGateLimits limits;
    limits.max_body_bytes = kMaxBodyBytes;
    limits.request_read_time = options.request_read_time;
    if (tls) {
        auto https = std::make_unique<GatedServer<httplib::SSLServer>>(
            limits, options.tls_cert.c_str(), options.tls_key.c_str());
        server->gate = &https->gate();
        server->http = std::move(https);
        if (!server->http->is_valid()) {
            return absl::FailedPreconditionError(
                absl::StrCat("--http ", host_port, ": cannot use --tls-cert ", options.tls_cert,
                             " and --tls-key ", options.tls_key, " for HTTPS"));
        }
    } else {
        auto plain = std::make_unique<GatedServer<httplib::Server>>(limits);
        server->gate = &plain->gate();
        server->http = std::move(plain);
    }
    httplib::Server& http = *server->http;
    // httplib sets SO_REUSEPORT, with which a second server would share the port and answer
    // scrapes at random: only SO_REUSEADDR, so that a port in use is an error.
    http.set_socket_options([](socket_t sock) {
        int yes = 1;
        setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    // For the Keep-Alive header; the gate keeps the time.
    http.set_keep_alive_timeout(absl::ToInt64Seconds(limits.keep_alive));
    http.set_keep_alive_max_count(size_t(limits.max_requests_per_connection));
    http.set_payload_max_length(kMaxBodyBytes);
    http.set_error_handler(httplib::Server::HandlerWithResponse(CutOff));
    auto answer = [&farm](HttpAnswer (*handler)(Farm&)) {
        return [&farm, handler](const httplib::Request&, httplib::Response& response) {
            Reply(handler(farm), response);
        };
    };
    http.Get("/healthz", answer(&HealthzAnswer));
    http.Get("/metrics", answer(&MetricsAnswer));
    if (options.dashboard_auth) {
        server->dashboard =
            std::make_unique<Dashboard>(farm, *options.dashboard_auth, DashboardOptions{tls});
        Dashboard* dashboard = server->dashboard.get();
        auto serve = [dashboard](const httplib::Request& request, httplib::Response& response) {
            // A chunked body may pass the gate's byte limit by its chunks' framing.
            Reply(request.body.size() > kMaxBodyBytes ? BodyTooLarge()
                                                      : dashboard->Serve(FromHttplib(request)),
                  response);
        };
        http.Get("/|/web/.*|/api/.*", serve);
        http.Post("/api/.*", serve);
    }
    const bool bound =
        port == 0 ? (port = http.bind_to_any_port(host)) > 0 : http.bind_to_port(host, port);
    if (!bound) {
        return absl::FailedPreconditionError(absl::StrCat(
            "cannot listen on ", host_port, " for --http (is another process using the port?)"));
    }
    server->thread = std::thread([&http] { http.listen_after_bind(); });
    // stop() does nothing until the loop runs: wait for it, so the destructor can end it.
    while (!http.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    Log()->info("serving /healthz, /metrics{} on {}://{}:{}",
                options.dashboard_auth ? " and the dashboard" : "", tls ? "https" : "http", host,
                port);
    return std::unique_ptr<HttpListener>(new HttpListener(std::move(server), port));
}

HttpListener::~HttpListener() {
    server_->http->stop();
    server_->thread.join();
    server_->gate->Stop();
}

}  // namespace lf
