// lightfarm-worker: renders tasks for a lightfarm-server until SIGTERM. See docs/farm.md.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <thread>

#include "absl/strings/str_cat.h"
#include "lf/core/log.h"
#include "lf/core/stop_signals.h"
#include "lf/job/worker_status.h"
#include "worker/worker.h"

int main(int argc, char** argv) {
    const lf::StopSignals stop_signals;  // before any thread starts

    CLI::App app{"lightfarm-worker: renders tasks of a lightfarm-server (see docs/farm.md)."};
    std::string server;
    lf::WorkerOptions options;
    options.threads = int(std::max(1u, std::thread::hardware_concurrency()));
    std::string cache_dir = "/tmp/lightfarm-worker-cache";
    uint64_t cache_mb = 2048;
    std::string log_level = "info";
    char host[256] = "worker";
    gethostname(host, sizeof host - 1);
    std::string name = host;
    app.add_option("--server", server, "HOST:PORT of the server")->required();
    app.add_option("--name", name, "what `lightfarm workers` calls this worker")
        ->capture_default_str()
        ->check([](const std::string& n) {
            return n.size() <= lf::kMaxWorkerNameBytes
                       ? std::string()
                       : absl::StrCat("at most ", lf::kMaxWorkerNameBytes, " bytes");
        });
    app.add_option("--threads", options.threads, "render threads")
        ->capture_default_str()
        ->check(CLI::Range(1, 1024));
    app.add_option("--cache-dir", cache_dir, "scene blob cache, one per worker (kept across runs)")
        ->capture_default_str();
    app.add_option("--cache-mb", cache_mb, "cache budget in MiB")->capture_default_str();
    app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
        ->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    spdlog::set_default_logger(spdlog::stderr_color_mt("worker"));
    spdlog::set_level(spdlog::level::from_str(log_level));
    absl::StatusOr<std::unique_ptr<lf::BlobCache>> cache =
        lf::BlobCache::Open(cache_dir + "/blobs", cache_mb << 20);
    if (!cache.ok()) {
        std::fprintf(stderr, "lightfarm-worker: error: %s\n",
                     std::string(cache.status().message()).c_str());
        return 1;
    }
    const std::string id = std::string(host) + "-" + std::to_string(::getpid());
    lf::ServerConnection connection(server, id, name);
    lf::Worker worker(options, connection, **cache);
    spdlog::info("worker={} ({}) serving {} with {} threads", id, lf::LogSafe(name), server,
                 options.threads);

    std::thread signal_waiter([&] {
        const int signal = stop_signals.Wait();
        spdlog::info("worker={} signal {}: handing back the task and stopping", id, signal);
        worker.Stop();
    });
    worker.Run();
    signal_waiter.join();
    return 0;
}
