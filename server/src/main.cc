// lightfarm-server: the farm's coordinator. Holds jobs, hands tasks to workers, merges their
// results and serves the images. See docs/farm.md.
#include <ImfThreading.h>
#include <grpcpp/grpcpp.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <thread>

#include "lf/core/stop_signals.h"
#include "lf/job/splat_settings.h"
#include "lf/proto/channel.h"
#include "lf/server/farm.h"
#include "lf/server/grpc_service.h"
#include "lf/server/health_port.h"
#include "lf/server/health_service.h"
#include "lf/server/http_listener.h"
#include "lf/server/listen_policy.h"
#include "lf/server/retention_flag.h"
#include "lf/server/server_credentials.h"
#include "lf/server/timeout_checker.h"
#include "lf/server/token_command.h"
#include "lf/server/token_store.h"
#include "lf/version.h"

int main(int argc, char** argv) {
    const lf::StopSignals stop_signals;  // before any thread starts

    CLI::App app{"lightfarm-server: the render farm's coordinator (see docs/farm.md)."};
    app.set_version_flag("--version", std::string(lf::kVersion));
    std::string listen = "127.0.0.1:7070";
    lf::FarmOptions options;
    double lease_seconds = 10;
    std::string log_level = "info";
    app.add_option("--listen", listen, "HOST:PORT to serve on; port 0 picks a free one")
        ->capture_default_str();
    app.add_option("--data-dir", options.data_dir,
                   "folder for jobs, blobs, results and tokens (required to serve)");
    lf::ServerTlsFiles tls;
    app.add_option("--tls-cert", tls.cert,
                   "PEM certificate (chain) of the server: TLS on the gRPC port");
    app.add_option("--tls-key", tls.key, "PEM private key of --tls-cert");
    app.add_option("--tls-client-ca", tls.client_ca,
                   "PEM CA of client certificates: workers must present one it signed (mutual "
                   "TLS); other clients may, and a certificate of another CA is refused");
    bool insecure = false;
    app.add_flag("--insecure", insecure,
                 "allow listening beyond loopback without TLS (the traffic and its tokens are "
                 "readable on the network)");
    bool check_config = false;
    app.add_flag("--check-config", check_config,
                 "check the options, the TLS files and the data folder, print \"config ok\" and "
                 "exit without serving");
    app.add_option("--lease-seconds", lease_seconds,
                   "a task goes back to the queue when its worker is silent this long")
        ->capture_default_str()
        ->check(CLI::Range(0.2, 3600.0));
    double speculate_seconds = absl::ToDoubleSeconds(options.scheduler.speculate_after);
    app.add_option("--speculate-seconds", speculate_seconds,
                   "near a job's end, a task running this long (and twice the job's mean) is "
                   "leased again to an idle worker")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    uint64_t max_scene_mb = options.limits.max_scene_bytes >> 20;
    app.add_option("--max-scene-mb", max_scene_mb, "largest scene, files included, per job")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--max-resolution", options.limits.max_resolution,
                   "largest image width and height per job")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--max-spp", options.limits.max_spp, "most samples per pixel per job")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--inline-radiosity-bytes", options.inline_radiosity_bytes,
                   "a radiosity sweep's input up to this size goes with the leases; larger (or "
                   "with 0, always) it is stored as a blob the workers fetch")
        ->capture_default_str()
        ->check(CLI::Range(size_t(0), lf::kMaxInlineRadiosityBytes));
    // A duration flag's check: 7d, 12h, 30m, 1d12h or 0 (lf::ParseRetention).
    const CLI::Validator duration(
        [](std::string& text) {
            absl::StatusOr<absl::Duration> d = lf::ParseRetention(text);
            return d.ok() ? std::string() : std::string(d.status().message());
        },
        "DURATION");
    double retention_days = 30;
    CLI::Option* days_option =
        app.add_option("--retention-days", retention_days,
                       "ended jobs older than this are deleted, with their results; 0 keeps "
                       "them forever")
            ->capture_default_str()
            ->check(CLI::NonNegativeNumber);
    std::string retention_text;
    app.add_option("--retention", retention_text,
                   "as --retention-days, as a duration: 7d, 12h, 30m, 1d12h; 0 keeps them forever")
        ->excludes(days_option)
        ->check(duration);
    std::string forget_workers_after = "1h";
    app.add_option("--forget-workers-after", forget_workers_after,
                   "a worker silent for a lease is listed as offline, with its last-seen time, "
                   "until this long after it was last seen (1h, 30m, 2d); 0 forgets it at once")
        ->capture_default_str()
        ->check(duration);
    app.add_option("--notify-url", options.notify_url,
                   "POST a JSON object ({job_id, name, owner, state, error, submitted, started, "
                   "finished}) to this http:// or https:// URL when a job succeeds, fails or is "
                   "cancelled; sent from its own thread, 3 attempts of 5 s at most each");
    lf::JobServiceOptions service_options;
    app.add_option("--max-watchers", service_options.max_watchers,
                   "most WatchJob streams open at once (each holds a thread); more are refused")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--max-watchers-per-token", service_options.max_watchers_per_token,
                   "most WatchJob streams one token may hold open at once")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--max-uploads-per-token", service_options.max_uploads_per_token,
                   "most UploadBlob streams one token may hold open at once (the farm keeps at "
                   "most 16 partial uploads)")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--max-fetches-per-token", service_options.max_fetches_per_token,
                   "most FetchResult streams one token may hold open at once")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--max-active-jobs", options.scheduler.max_active_jobs,
                   "most jobs queued or running at once")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--max-leases-per-token", options.scheduler.max_leases_per_token,
                   "most tasks the workers of one worker token hold at once (whatever worker ids "
                   "they claim); a worker whose leases expire unheard 3 times in a row gets none "
                   "for 10 leases' time")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    std::string http;
    std::string grpc_health;
    app.add_option("--grpc-health", grpc_health,
                   "HOST:PORT of a plain-text gRPC port that serves only grpc.health.v1.Health, "
                   "for probes that cannot speak TLS (Kubernetes' grpc probe); off if unset");
    app.add_option("--http", http,
                   "HOST:PORT to serve GET /healthz, /metrics (Prometheus) and the web dashboard "
                   "on, over HTTPS with --tls-cert and --tls-key; off if unset. A request must "
                   "arrive whole within 10 s (bodies at most 64 KiB); /healthz has a thread of "
                   "its own");
    app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
        ->capture_default_str();
    lf::TokenCommand token_command(app);
    CLI11_PARSE(app, argc, argv);
    if (std::optional<int> status = token_command.Run()) return *status;
    const auto fail = [](const absl::Status& s) {
        std::fprintf(stderr, "lightfarm-server: error: %s\n", std::string(s.message()).c_str());
        return 1;
    };
    if (options.data_dir.empty()) {
        return fail(absl::InvalidArgumentError("--data-dir is required"));
    }
    if (absl::Status s = lf::CheckListenPolicy(listen, tls.enabled(), insecure); !s.ok()) {
        return fail(s);
    }
    absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials =
        lf::MakeServerCredentials(tls);
    if (!credentials.ok()) return fail(credentials.status());
    absl::StatusOr<std::unique_ptr<lf::TokenStore>> tokens = lf::TokenStore::Open(options.data_dir);
    if (!tokens.ok()) return fail(tokens.status());
    // Beyond loopback every call needs a token, even before the first one is made.
    const bool auth_required = !lf::IsLoopbackHost(lf::ListenHost(listen));
    if (check_config) {
        std::printf("config ok\n");
        return 0;
    }

    spdlog::set_default_logger(spdlog::stderr_color_mt("server"));
    spdlog::set_level(spdlog::level::from_str(log_level));
    options.scheduler.lease = absl::Seconds(lease_seconds);
    options.scheduler.speculate_after = absl::Seconds(speculate_seconds);
    options.limits.max_scene_bytes = max_scene_mb << 20;
    options.scheduler.forget_workers_after = *lf::ParseRetention(forget_workers_after);
    options.retention = retention_text.empty() ? absl::Hours(24 * retention_days)
                                               : *lf::ParseRetention(retention_text);
    // Often enough that a cancel reaches workers within about a second, and several times per
    // lease so one slow answer does not lose it.
    options.scheduler.heartbeat_interval =
        std::min(absl::Milliseconds(300), options.scheduler.lease / 4);

    // A job's EXR is written as the last step before it ends (its ZIP compression is most of
    // that step): its line blocks are compressed on every core, to the same bytes as on one.
    Imf::setGlobalThreadCount(int(std::max(1u, std::thread::hardware_concurrency())));

    absl::StatusOr<std::unique_ptr<lf::Farm>> farm = lf::Farm::Open(options);
    if (!farm.ok()) return fail(farm.status());
    lf::Authenticator auth(std::move(*tokens), auth_required);
    const lf::CallGuard guard{auth, !tls.client_ca.empty()};
    lf::JobServiceImpl job_service(**farm, guard, service_options);
    lf::WorkerServiceImpl worker_service(**farm, guard);
    // grpc.health.v1.Health: SERVING while the server runs, NOT_SERVING from shutdown on. It
    // answers without a token, as Kubernetes' gRPC probes and load balancers ask.
    lf::HealthService health_service;
    grpc::ServerBuilder builder;
    int port = 0;
    // Without SO_REUSEPORT a second server on this port fails here, instead of sharing the
    // port and answering clients at random.
    builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
    // Clients and workers ping every lf::kKeepaliveInterval to find dead links
    // (lf/proto/channel.h); gRPC's default would answer pings that often with GOAWAY.
    builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
    builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS,
                               int(lf::kKeepaliveInterval / absl::Milliseconds(2)));
    builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 0);
    // A splat task's result (camera sums and splats) may be far above gRPC's 4 MiB default; the
    // bound is the largest one the plans make (lf::kMaxTaskResultBytes, docs/farm.md).
    builder.SetMaxReceiveMessageSize(lf::kMaxTaskResultBytes);
    builder.AddListeningPort(listen, *credentials, &port);
    builder.RegisterService(&job_service);
    builder.RegisterService(&worker_service);
    builder.RegisterService(&health_service);
    std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
    if (!server || port == 0) {
        std::fprintf(stderr,
                     "lightfarm-server: error: cannot listen on %s (is another server using "
                     "the port?)\n",
                     listen.c_str());
        return 1;
    }
    const std::string host = listen.substr(0, listen.rfind(':'));
    std::printf("listening on %s:%d\n", host.c_str(), port);
    std::fflush(stdout);
    spdlog::info(
        "listening on {}:{} ({}), data in {}, leases of {} s", host, port,
        tls.enabled() ? (tls.client_ca.empty() ? "TLS" : "TLS, worker certificates") : "no TLS",
        options.data_dir, lease_seconds);
    if (auth.enabled()) {
        spdlog::info("authentication on: every call needs a token ({})",
                     auth_required ? "listening beyond loopback" : "tokens exist");
    } else {
        spdlog::warn(
            "authentication off: no tokens in {}/{} and listening on loopback; anyone "
            "on this machine may use the farm",
            options.data_dir, lf::TokenStore::kFileName);
    }
    // Health alone, in plain text: it tells whether the server runs and nothing else, so it
    // needs neither TLS nor a token.
    std::optional<lf::HealthPort> health_port;
    if (!grpc_health.empty()) {
        absl::StatusOr<lf::HealthPort> health = lf::StartHealthPort(grpc_health);
        if (!health.ok()) return fail(health.status());
        health_port = std::move(*health);
        std::printf("grpc health on %s:%d\n", grpc_health.substr(0, grpc_health.rfind(':')).c_str(),
                    health_port->port);
        std::fflush(stdout);
    }
    // Health and farm-wide counts without a token; the dashboard behind the same tokens (and
    // the same certificate) as the gRPC port, and under the same rule: beyond loopback, tokens
    // travel only over TLS unless --insecure.
    std::unique_ptr<lf::HttpListener> http_listener;
    if (!http.empty()) {
        const bool dashboard = lf::CheckListenPolicy(http, tls.enabled(), insecure).ok();
        if (!dashboard) {
            spdlog::warn(
                "--http {}: the dashboard is off: beyond loopback it needs TLS (--tls-cert, "
                "--tls-key) or --insecure; /healthz and /metrics are served",
                http);
        }
        absl::StatusOr<std::unique_ptr<lf::HttpListener>> started =
            lf::HttpListener::Start(http, **farm,
                                    {.dashboard_auth = dashboard ? &auth : nullptr,
                                     .tls_cert = tls.cert,
                                     .tls_key = tls.key});
        if (!started.ok()) return fail(started.status());
        http_listener = std::move(*started);
        // Port 0 picks one: say which, as for --listen.
        std::printf("http on %s:%d\n", http.substr(0, http.rfind(':')).c_str(),
                    http_listener->port());
        std::fflush(stdout);
    }

    // Expired leases go back to the queue, and adaptive jobs past their time limit stop
    // sampling, within a tenth of a second.
    lf::TimeoutChecker timeout_checker(absl::Milliseconds(100), [&] { (*farm)->CheckTimers(); });

    // Retention: the jobs that expire while the server runs go within the hour.
    lf::TimeoutChecker retention(absl::Hours(1), [&] {
        if (absl::StatusOr<int> n = (*farm)->DeleteExpired(absl::Now()); !n.ok()) {
            spdlog::error("retention: {}", std::string(n.status().message()));
        }
    });

    spdlog::info("signal {}: shutting down", stop_signals.Wait());
    health_service.SetServing(false);
    if (health_port) health_port->health->SetServing(false);
    (*farm)->scheduler().Shutdown();
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
    if (health_port) health_port->server->Shutdown(std::chrono::system_clock::now());
    timeout_checker.Stop();
    retention.Stop();
    return 0;
}
