// lightfarm-worker: renders tasks for a lightfarm-server until SIGTERM. See docs/farm.md.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "absl/strings/str_cat.h"
#include "lf/core/dir_lock.h"
#include "lf/core/log.h"
#include "lf/core/plural.h"
#include "lf/core/stop_signals.h"
#include "lf/job/worker_status.h"
#include "lf/job/worker_tags.h"
#include "lf/proto/channel_flags.h"
#include "lf/version.h"
#include "lf/worker/worker.h"

int main(int argc, char** argv) {
    const lf::StopSignals stop_signals;  // before any thread starts

    CLI::App app{"lightfarm-worker: renders tasks of a lightfarm-server (see docs/farm.md)."};
    app.set_version_flag("--version", std::string(lf::kVersion));
    lf::ChannelOptions channel;
    lf::WorkerOptions options;
    options.threads = int(std::max(1u, std::thread::hardware_concurrency()));
    std::string cache_dir = "/tmp/lightfarm-worker-cache";
    uint64_t cache_mb = 2048;
    std::string log_level = "info";
    char host[256] = "worker";
    gethostname(host, sizeof host - 1);
    std::string name = host;
    app.add_option("--server", channel.address, "HOST:PORT of the server")
        ->envname("LIGHTFARM_SERVER")
        ->required();
    lf::AddChannelFlags(&app, &channel);
    app.add_option("--name", name, "what `lightfarm workers` calls this worker")
        ->capture_default_str()
        ->check([](const std::string& n) {
            return n.size() <= lf::kMaxWorkerNameBytes
                       ? std::string()
                       : absl::StrCat("at most ", lf::kMaxWorkerNameBytes, " bytes");
        });
    std::string tags;
    app.add_option("--tags", tags,
                   "comma-separated tags of this worker (gpu,big-memory: each [a-z0-9_-]{1,32}, at "
                   "most 32); it takes only jobs whose every tag it has (submit --tags)")
        ->check([](const std::string& list) {
            const absl::StatusOr<std::vector<std::string>> parsed = lf::ParseTags(list, "--tags");
            return parsed.ok() ? std::string() : std::string(parsed.status().message());
        });
    bool check_config = false;
    app.add_flag("--check-config", check_config,
                 "check the options, the TLS and token files and the cache folder, print "
                 "\"config ok\" and exit without connecting");
    app.add_option("--threads", options.threads, "render threads")
        ->capture_default_str()
        ->check(CLI::Range(1, 1024));
    app.add_option("--cache-dir", cache_dir,
                   "scene blob cache (kept across runs), one per worker: a worker refuses a folder "
                   "another running worker holds (its lock file names the holder's pid)")
        ->capture_default_str();
    app.add_option("--cache-mb", cache_mb, "cache budget in MiB")->capture_default_str();
    app.add_option("--log-level", log_level,
                   "what stderr shows: trace, debug, info, warn, error or off (each task's log "
                   "for the server keeps info and above in any case)")
        ->capture_default_str();
    // Hidden (no group): for the farm's tests of retries and the blocklist only.
    app.add_flag("--fail-tasks-for-test", options.fail_tasks_for_test,
                 "tests only: fail every task at once")
        ->group("");
    CLI11_PARSE(app, argc, argv);

    const auto fail = [](const absl::Status& s) {
        std::fprintf(stderr, "lightfarm-worker: error: %s\n", std::string(s.message()).c_str());
        return 1;
    };
    const spdlog::level::level_enum level = spdlog::level::from_str(log_level);
    spdlog::set_default_logger(spdlog::stderr_color_mt("worker"));
    // --log-level is what stderr shows. The loggers pass info and above whatever it is: a task's
    // log on the server (lightfarm logs) says what the task did even on a quiet worker.
    spdlog::default_logger()->sinks().front()->set_level(level);
    spdlog::set_level(std::min(level, spdlog::level::info));
    // Before any other logger is made: each clones the default logger's sinks.
    const std::shared_ptr<lf::TaskLogSink> task_logs = lf::TaskLogSink::Install();
    // One worker per cache: two would evict each other's blobs mid-fetch.
    std::error_code made;
    std::filesystem::create_directories(cache_dir, made);
    if (made) return fail(absl::InternalError(cache_dir + ": " + made.message()));
    absl::StatusOr<std::unique_ptr<lf::DirLock>> cache_lock =
        lf::DirLock::Acquire(cache_dir, {"cache folder", "lightfarm-worker", "--cache-dir"});
    if (!cache_lock.ok()) return fail(cache_lock.status());
    absl::StatusOr<std::unique_ptr<lf::BlobCache>> cache =
        lf::BlobCache::Open(cache_dir + "/blobs", cache_mb << 20);
    if (!cache.ok()) return fail(cache.status());
    const std::string id = std::string(host) + "-" + std::to_string(::getpid());
    absl::StatusOr<std::unique_ptr<lf::ServerConnection>> connection =
        lf::ServerConnection::Open(channel, id, name);
    if (!connection.ok()) return fail(connection.status());
    (*connection)->set_tags(*lf::ParseTags(tags, "--tags"));  // checked by the flag
    if (check_config) {
        std::printf("config ok\n");
        return 0;
    }
    lf::Worker worker(options, **connection, **cache, *task_logs);
    spdlog::info("worker={} ({}) serving {} with {} ({})", id, lf::LogSafe(name), channel.address,
                 lf::Plural(options.threads, "thread"), channel.tls_ca.empty() ? "no TLS" : "TLS");

    std::thread signal_waiter([&] {
        const int signal = stop_signals.Wait();
        spdlog::info("worker={} signal {}: handing back the task and stopping", id, signal);
        worker.Stop();
    });
    worker.Run();
    signal_waiter.join();
    return 0;
}
