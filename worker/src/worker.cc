#include "lf/worker/worker.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/file_util.h"
#include "lf/core/log.h"
#include "lf/core/plural.h"
#include "lf/core/radiosity_codec.h"
#include "lf/core/scene_animation.h"
#include "lf/core/splat_codec.h"
#include "lf/core/tile_codec.h"
#include "lf/job/adaptive_plan.h"
#include "lf/job/method_registry.h"
#include "lf/job/shot.h"
#include "lf/job/splat_settings.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/tile_renderer.h"
#include "lf/local/method_factory.h"

namespace lf {

namespace {

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("worker"); }

// A task's wall and CPU time since it was made. The CPU time is the whole process': a worker
// runs one task at a time, and besides it only the heartbeats and the upload of the previous
// result, which cost little.
class TaskClock {
  public:
    TaskClock() : wall_(std::chrono::steady_clock::now()), cpu_(ProcessCpuSeconds()) {}
    // The steady clock: a step of the system clock during the task changes nothing.
    TaskTimes Elapsed() const {
        return {std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_).count(),
                ProcessCpuSeconds() - cpu_};
    }

  private:
    static double ProcessCpuSeconds() {
        timespec t{};
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
        return double(t.tv_sec) + double(t.tv_nsec) * 1e-9;
    }
    std::chrono::steady_clock::time_point wall_;
    double cpu_;
};

// What a lease asks for, for its first log line.
std::string DescribeTask(const TaskAssignment& task) {
    if (task.sweep >= 0) {
        return absl::StrCat("radiosity sweep ", task.sweep, " patch group",
                            task.chunks.size() == 1 ? " " : "s ", absl::StrJoin(task.chunks, ", "),
                            " of ", task.spec.radiosity.sweep_tasks);
    }
    const PixelRect& r = task.task.rect;
    std::string what =
        absl::StrCat(task.spec.method, ", pixels ", r.x0, ",", r.y0, " ", r.width, "x", r.height,
                     ", samples ", task.task.sample_begin, "-", task.task.sample_end, " (",
                     task.task.sample_end - task.task.sample_begin, " spp)");
    if (task.path_end > task.path_begin) {
        absl::StrAppend(&what, ", light paths ", task.path_begin, "-", task.path_end);
    }
    if (task.frame) absl::StrAppend(&what, ", frame ", *task.frame);
    if (!task.parts.empty()) {
        what = absl::StrCat(task.spec.method, ", frames ", task.parts.front().frame, "-",
                            task.parts.back().frame, " whole (", task.parts.size(), " parts)");
    }
    return what;
}

}  // namespace

Worker::Worker(WorkerOptions options, ServerConnection& server, BlobCache& cache, TaskLogSink& logs)
    : options_(std::move(options)),
      server_(server),
      cache_(cache),
      logs_(logs),
      arena_(options_.threads),
      sender_([this] { SenderLoop(); }) {}

Worker::~Worker() {
    {
        std::lock_guard<std::mutex> lock(send_mutex_);
        sender_stop_ = true;
    }
    send_cv_.notify_all();
    sender_.join();  // sends what was handed over first
}

void Worker::Stop() {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
    if (current_cancel_) current_cancel_->store(true);
    wake_.notify_all();
}

void Worker::WaitIdle(absl::Duration d) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait_for(lock, absl::ToChronoNanoseconds(d), [&] { return stopping(); });
}

void Worker::Run() {
    absl::Duration idle = options_.min_idle;
    absl::StatusCode last = absl::StatusCode::kOk;  // logged when it changes, not every retry
    while (!stopping()) {
        absl::StatusOr<std::optional<TaskAssignment>> task = server_.Lease(options_.lease_wait);
        if (task.status().code() != last) {
            last = task.status().code();
            const std::string why(task.status().message());
            if (task.ok()) {
                Log()->info("worker={} server reachable again", server_.worker_id());
            } else if (last == absl::StatusCode::kFailedPrecondition) {
                // Another build (LeaseTask's version check) or TLS on one side only. Retried
                // rather than exiting, so a server fixed gets its workers back without restarts.
                Log()->error("worker={} cannot work with the server, retrying until it can: {}",
                             server_.worker_id(), why);
            } else if (last == absl::StatusCode::kUnauthenticated ||
                       last == absl::StatusCode::kPermissionDenied) {
                // A token or certificate the server does not take (yet): retried, so that
                // creating the token or fixing the server's CA needs no worker restart.
                Log()->error("worker={} refused by the server, retrying: {}", server_.worker_id(),
                             why);
            } else {
                Log()->warn("worker={} server unreachable, retrying: {}", server_.worker_id(), why);
            }
        }
        if (!task.ok()) {
            WaitIdle(idle);
            idle = std::min(idle * 2, options_.max_idle);
            continue;
        }
        idle = options_.min_idle;
        if (!*task) continue;  // the server already waited
        Execute(**task);
    }
    FlushSends();  // a result finished before the stop is still worth its upload
    Log()->info("worker={} stopped", server_.worker_id());
}

void Worker::Execute(const TaskAssignment& task) {
    // Everything logged from here until End, the kernels' lines included, is the task's.
    const std::shared_ptr<TaskLog> log = logs_.Begin();
    const std::string ids = "job=" + task.job_id + " task=" + std::to_string(task.task.index);
    Log()->info("{} leased: {}", ids, DescribeTask(task));
    std::atomic<bool> cancel{false};
    {
        std::lock_guard<std::mutex> lock(mutex_);
        current_cancel_ = &cancel;
        if (stopping()) cancel = true;
    }
    // Heartbeats from their own thread, so a long tile keeps its lease and hears of a cancel.
    // The first goes at once: it tells the coordinator the task was taken (a lease that expires
    // before any heartbeat is held against the worker, not the task). But a sweep of links this
    // worker holds is a few milliseconds of arithmetic on what it computed already: its result
    // says the same, so its first heartbeat waits an interval (one RPC a worker and sweep fewer).
    std::mutex hb_mutex;
    std::condition_variable hb_wake;
    bool task_over = false;
    std::atomic<bool> dropped{false};
    const bool quick = SweepsHeldLinks(task);
    std::thread heartbeat([&] {
        std::unique_lock<std::mutex> lock(hb_mutex);
        if (quick && hb_wake.wait_for(lock, absl::ToChronoNanoseconds(task.heartbeat_interval),
                                      [&] { return task_over; })) {
            return;
        }
        while (!task_over) {
            lock.unlock();
            // Lines of a heartbeat that does not arrive are lost: the next one carries newer.
            const absl::StatusOr<bool> keep = server_.Heartbeat(task.lease_id, log->Take());
            lock.lock();
            if (keep.ok() && !*keep) {
                dropped = true;
                cancel = true;
            }
            if (hb_wake.wait_for(lock, absl::ToChronoNanoseconds(task.heartbeat_interval),
                                 [&] { return task_over; })) {
                break;
            }
        }
    });

    const TaskClock clock;
    ServerConnection::TaskResult result;
    RenderStats stats;
    // The task's own fields first: a malformed one fails before any download.
    absl::Status status = options_.fail_tasks_for_test
                              ? absl::InternalError("failing every task (--fail-tasks-for-test)")
                              : CheckActivePixels(task.task, task.spec.adaptive);
    if (status.ok()) status = PrepareScene(task, cancel);
    if (status.ok()) status = RunTask(task, cancel, result, stats);
    {
        std::lock_guard<std::mutex> lock(hb_mutex);
        task_over = true;
    }
    hb_wake.notify_all();
    heartbeat.join();
    {
        std::lock_guard<std::mutex> lock(mutex_);
        current_cancel_ = nullptr;
    }

    result.times = clock.Elapsed();
    const double seconds = result.times.render_seconds;
    // A result that was finished before a stop was asked for is still worth sending.
    if (dropped) {
        Log()->info("{} dropped: the job was cancelled or the lease lost", ids);
        logs_.End();
    } else if (status.ok() && !cancel) {
        Log()->info("{} rendered in {:.2f} s: {} samples, {} rays, {} NaN/Inf samples", ids,
                    seconds, stats.samples, stats.rays, stats.invalid_samples);
        logs_.End();
        result.log = log->Take();
        SendResult(task, std::move(result), seconds);
    } else if (stopping()) {
        Log()->info("{} handed back: worker shutting down", ids);
        logs_.End();
        (void)server_.Fail(task.lease_id, "worker shutting down", true, log->Take());
    } else {
        Log()->error("{} failed after {:.2f} s: {}", ids, seconds, std::string(status.message()));
        logs_.End();
        (void)server_.Fail(task.lease_id, std::string(status.message()), false, log->Take());
    }
}

absl::Status Worker::RunTask(const TaskAssignment& task, const std::atomic<bool>& cancel,
                             ServerConnection::TaskResult& result, RenderStats& stats,
                             SplatList* frame_splats) {
    if (!task.parts.empty()) return RunChunk(task, cancel, result, stats);
    if (task.frame) {
        if (absl::Status s = PoseFrame(task, *task.frame, cancel); !s.ok()) return s;
        result.frame = task.frame;
    }
    if (task.sweep >= 0) {
        std::optional<RadiosityFigures> figures;
        absl::StatusOr<std::string> swept = Sweep(task, cancel, figures);
        if (!swept.ok()) return swept.status();
        result = {std::move(*swept), true, figures};
        return absl::OkStatus();
    }
    if (UsesSplatPlan(task.spec.method)) {
        return RenderSplat(task, cancel, result, stats, frame_splats);
    }
    if (absl::Status s = PrepareTracer(task, cancel); !s.ok()) return s;
    const TileSums sums = Render(task, cancel);
    stats = sums.stats;
    result.bytes = EncodeTileSums(sums);
    if (const auto* r = dynamic_cast<const RadiosityRenderer*>(loaded_.tracer.get())) {
        result.radiosity = RadiosityFiguresOf(r->report());
    }
    return absl::OkStatus();
}

absl::Status Worker::RunChunk(const TaskAssignment& task, const std::atomic<bool>& cancel,
                              ServerConnection::TaskResult& result, RenderStats& stats) {
    TaskAssignment one = task;
    one.parts.clear();
    // A splatting method's parts add their splats to one list a frame: its exact sums are the
    // same whichever task added what, and it holds at most 2 entries a pixel however many tasks
    // the frame has, so a chunk's result is bounded by its frames (lf::CheckShotChunk). The
    // frame's first part carries the list, its others an empty one.
    const bool splatting = UsesSplatPlan(task.spec.method);
    std::map<int, SplatList> frame_splats;
    std::map<int, size_t> first_part;
    for (const TaskAssignment::Part& part : task.parts) {
        if (cancel) return absl::CancelledError("chunk cancelled");
        one.task.rect = part.task.rect;
        one.task.sample_begin = part.task.sample_begin;
        one.task.sample_end = part.task.sample_end;
        one.path_begin = part.path_begin;
        one.path_end = part.path_end;
        one.frame = part.frame;
        ServerConnection::TaskResult rendered;
        RenderStats part_stats;
        SplatList* splats = nullptr;
        if (splatting) {
            splats = &frame_splats[part.frame];
            first_part.try_emplace(part.frame, result.parts.size());
        }
        const TaskClock clock;
        if (absl::Status s = RunTask(one, cancel, rendered, part_stats, splats); !s.ok()) return s;
        stats += part_stats;
        if (rendered.radiosity) result.radiosity = rendered.radiosity;
        result.parts.push_back(
            {part.frame, std::move(rendered.bytes), std::move(rendered.splats), clock.Elapsed()});
    }
    if (!splatting) return absl::OkStatus();
    size_t bytes = 0;
    for (size_t i = 0; i < result.parts.size(); ++i) {
        ServerConnection::TaskResult::Part& part = result.parts[i];
        SplatList& list = frame_splats[part.frame];
        SplatList none(list.width(), list.height());
        part.splats = EncodeSplatList(first_part[part.frame] == i ? list : none);
        bytes += part.bytes.size() + part.splats->size();
    }
    if (bytes > size_t(kMaxTaskResultBytes) - 4096) {
        return absl::FailedPreconditionError(absl::StrCat(
            "the result of job ", task.job_id, " task ", task.task.index, " (", task.parts.size(),
            " parts) is ", bytes, " bytes, above the coordinator's bound of ", kMaxTaskResultBytes,
            " (lf::kMaxTaskResultBytes): submit with a smaller --chunk"));
    }
    return absl::OkStatus();
}

absl::Status Worker::PoseFrame(const TaskAssignment& task, int frame,
                               const std::atomic<bool>& cancel) {
    if (loaded_.posed_frame == frame) return absl::OkStatus();
    const SceneAnimation* animation = loaded_.scene->animation.get();
    // Without motion every time gives the image of the first pose: the BVH built for it stays,
    // and so do the kernels (a radiosity solve included).
    const bool moves = animation && animation->Moves();
    if (loaded_.embree && !moves) {
        loaded_.posed_frame = frame;
        Log()->info("job={} task={} frame {}: nothing moves, the scene and BVH are kept",
                    task.job_id, task.task.index, frame);
        return absl::OkStatus();
    }
    const absl::Time start = absl::Now();
    if (absl::Status s = PoseSceneAtFrame(frame, task.spec.shot, *loaded_.scene); !s.ok()) {
        loaded_ = {};  // perhaps half posed: loaded again for the next task
        return s;
    }
    const absl::Time posed = absl::Now();
    loaded_.tracer.reset();
    loaded_.frame.reset();
    loaded_.camera.reset();
    loaded_.embree.reset();
    loaded_.posed_frame.reset();
    // Under an open shutter the BVH holds the poses over it, as `render --shutter` builds them.
    const ShutterInterval shutter = ShutterOf(frame, task.spec.shot);
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(
        *loaded_.scene, &cancel, {loaded_.scene->animation.get(), shutter.open, shutter.close});
    if (!embree.ok()) return embree.status();
    loaded_.embree = std::move(*embree);
    loaded_.camera = std::make_unique<Camera>(loaded_.scene->camera, loaded_.embree->origin(),
                                              loaded_.embree->camera_motion());
    loaded_.posed_frame = frame;
    Log()->info("job={} task={} frame {} posed in {:.1f} ms, BVH built in {:.1f} ms", task.job_id,
                task.task.index, frame, absl::ToDoubleMilliseconds(posed - start),
                absl::ToDoubleMilliseconds(absl::Now() - posed));
    return absl::OkStatus();
}

absl::Status Worker::PrepareScene(const TaskAssignment& task, const std::atomic<bool>& cancel) {
    if (loaded_.job_id == task.job_id) {
        Log()->info("job={} task={} scene {} already loaded", task.job_id, task.task.index,
                    task.spec.scene.path);
        return absl::OkStatus();
    }
    // The previous job's geometry and BVH go now, its decoded textures only after this load:
    // a texture the next job uses too (the next frame of a shot, say) is then shared, not
    // decoded again (DecodeTexture keeps each file content once while anything holds it).
    const std::vector<std::shared_ptr<const TextureImage>> previous_textures =
        loaded_.scene ? loaded_.scene->textures
                      : std::vector<std::shared_ptr<const TextureImage>>{};
    loaded_ = {};
    int fetched = 0;  // the others were in the cache
    auto fetch = [&](const std::string& hash, const std::string& path) {
        ++fetched;
        return server_.FetchBlob(hash, path);
    };
    std::vector<const BlobRef*> refs = {&task.spec.scene};
    for (const BlobRef& ref : task.spec.files) refs.push_back(&ref);
    std::map<std::string, std::string> files;  // hash -> cached file
    auto cancelled = [&] { return absl::CancelledError("scene loading cancelled"); };
    for (const BlobRef* ref : refs) {
        if (cancel) return cancelled();
        absl::StatusOr<std::string> path = cache_.Get(ref->hash, fetch);
        if (!path.ok()) return path.status();
        files[ref->hash] = *path;
    }
    absl::StatusOr<Scene> scene = LoadSceneFromBlobs(
        task.spec.scene, task.spec.files, [&](const std::string& hash) { return files[hash]; },
        &cancel, task.spec.scene_options);
    cache_.Trim();
    if (!scene.ok()) return scene.status();
    if (cancel) return cancelled();
    PrepareSceneFor(MethodOf(task.spec), *scene);
    LoadedScene loaded;
    loaded.scene = std::make_unique<Scene>(std::move(*scene));
    // A shot's BVH is built for its first frame's pose (PoseFrame), a still's for the rest pose.
    if (!task.spec.shot.frames) {
        absl::StatusOr<std::unique_ptr<EmbreeScene>> embree =
            EmbreeScene::Build(*loaded.scene, &cancel);
        if (!embree.ok()) return embree.status();
        loaded.embree = std::move(*embree);
        loaded.camera = std::make_unique<Camera>(loaded.scene->camera, loaded.embree->origin());
    }
    loaded.job_id = task.job_id;
    loaded_ = std::move(loaded);
    Log()->info("job={} task={} scene {} loaded: {}, {} fetched from the server, {} cached",
                task.job_id, task.task.index, task.spec.scene.path,
                Plural(int64_t(refs.size()), "file"), fetched, int(refs.size()) - fetched);
    return absl::OkStatus();
}

absl::Status Worker::PrepareTracer(const TaskAssignment& task, const std::atomic<bool>& cancel) {
    if (loaded_.tracer) return absl::OkStatus();
    const Method method = MethodOf(task.spec);
    if (Info(method).work != WorkKind::kRadiosity) {
        // Cached per job (loaded_.job_id), so the job's one light strategy is the tracer's.
        absl::StatusOr<std::unique_ptr<RadianceEstimator>> tracer =
            MakeRayTracer(method, *loaded_.embree, task.spec.max_depth, task.spec.light_strategy);
        if (!tracer.ok()) return tracer.status();
        loaded_.tracer = std::move(*tracer);
        return absl::OkStatus();
    }
    absl::StatusOr<RadiosityOptions> options =
        RadiosityOptionsOf(task.spec.radiosity, task.spec.adaptive.target_error);
    if (!options.ok()) return options.status();
    options->threads = options_.threads;
    options->cancel = &cancel;  // meshing, form factors and the solve stop on a cancel
    absl::StatusOr<std::unique_ptr<RadiosityRenderer>> renderer;
    if (!task.radiosity_hash.empty()) {  // solved by the farm's sweeps
        absl::StatusOr<std::vector<Rgb>> solution = ReadRadiosity(task);
        if (!solution.ok()) return solution.status();
        // The sweeps' mesh (and cluster tree) are those the display needs: the mesh moves over.
        renderer = loaded_.sweeps
                       ? std::move(*loaded_.sweeps)
                             .Renderer(*loaded_.embree, *options, std::move(*solution))
                       : RadiosityRendererFor(*loaded_.embree, *options, std::move(*solution));
    } else {
        // Every worker of the job solves the same system to the same bits (the solver is
        // deterministic for any thread count), so its tiles match `lightfarm render`.
        renderer = PrepareRadiosity(*loaded_.embree, *options);
    }
    // The sweeps are over: their form-factor rows are not needed again (and a holder whose
    // Renderer failed may have given its mesh away: a retry builds from the scene).
    loaded_.sweeps.reset();
    loaded_.input.clear();
    loaded_.input_hash.clear();
    loaded_.pulled.clear();
    loaded_.pulled_hash.reset();
    if (!renderer.ok()) return renderer.status();
    loaded_.tracer = std::move(*renderer);
    return absl::OkStatus();
}

bool Worker::SweepsHeldLinks(const TaskAssignment& task) const {
    if (task.sweep <= 0 || task.job_id != loaded_.job_id || !loaded_.sweeps) return false;
    for (int chunk : task.chunks) {
        if (!loaded_.sweeps->Linked(chunk)) return false;
    }
    return !task.chunks.empty();
}

absl::StatusOr<std::vector<Rgb>> Worker::ReadRadiosity(const TaskAssignment& task) {
    if (task.radiosity_input) return DecodeRadiosity(*task.radiosity_input);
    absl::StatusOr<std::string> path = cache_.Get(
        task.radiosity_hash,
        [&](const std::string& h, const std::string& p) { return server_.FetchBlob(h, p); });
    if (!path.ok()) return path.status();
    absl::StatusOr<std::string> bytes = ReadFile(*path);
    if (!bytes.ok()) return bytes.status();
    return DecodeRadiosity(*bytes);
}

absl::StatusOr<std::string> Worker::Sweep(const TaskAssignment& task,
                                          const std::atomic<bool>& cancel,
                                          std::optional<RadiosityFigures>& figures) {
    const RadiositySettings& r = task.spec.radiosity;
    if (task.chunks.empty()) return absl::InvalidArgumentError("a sweep task of no chunks");
    for (int chunk : task.chunks) {
        if (loaded_.sweeps && loaded_.sweeps->Linked(chunk)) continue;
        absl::StatusOr<RadiosityOptions> options =
            RadiosityOptionsOf(task.spec.radiosity, task.spec.adaptive.target_error);
        if (!options.ok()) return options.status();
        const absl::Time start = absl::Now();
        absl::Status linked;
        arena_.execute([&] {
            // The mesh and system (or cluster tree) once, for every chunk this worker gets.
            if (!loaded_.sweeps) {
                absl::StatusOr<std::unique_ptr<RadiositySweepChunks>> made =
                    RadiositySweepChunks::Make(*loaded_.embree, *options, r.sweep_tasks, &cancel);
                if (!made.ok()) {
                    linked = made.status();
                    return;
                }
                loaded_.sweeps = std::move(*made);
            }
            linked = loaded_.sweeps->Link(*loaded_.embree, chunk, &cancel);
        });
        if (!linked.ok()) return linked;
        Log()->info("job={} task={} form factors of chunk {}/{} in {:.2f} s", task.job_id,
                    task.task.index, chunk, r.sweep_tasks,
                    absl::ToDoubleSeconds(absl::Now() - start));
    }
    const RadiositySweepChunks& chunks = *loaded_.sweeps;
    std::span<const Rgb> input = chunks.start();
    if (!task.radiosity_hash.empty()) {
        if (loaded_.input_hash != task.radiosity_hash) {
            absl::StatusOr<std::vector<Rgb>> read = ReadRadiosity(task);
            if (!read.ok()) return read.status();
            loaded_.input = std::move(*read);
            loaded_.input_hash = task.radiosity_hash;
        }
        input = loaded_.input;
    }
    std::vector<SweepChunkResult> results;
    absl::Status swept;
    arena_.execute([&] {
        if (loaded_.pulled_hash != task.radiosity_hash) {
            loaded_.pulled = chunks.Pull(input);
            loaded_.pulled_hash = task.radiosity_hash;
        }
        for (int chunk : task.chunks) {
            if (cancel) {
                swept = absl::CancelledError("radiosity sweep cancelled");
                return;
            }
            absl::StatusOr<SweepChunkResult> result =
                chunks.Sweep(chunk, task.sweep, input, loaded_.pulled);
            if (!result.ok()) {
                swept = result.status();
                return;
            }
            results.push_back(std::move(*result));
        }
    });
    if (!swept.ok()) return swept;
    // A chunk's links (hierarchical), for the EXR header, go with its sweep-0 task, which is of
    // it alone.
    if (task.sweep == 0 && task.chunks.size() == 1) {
        const RadiosityReport links = chunks.LinkReport(task.chunks.front());
        if (links.solver_bytes > 0) figures = RadiosityFiguresOf(links);
    }
    return EncodeSweepResults(results);
}

TileSums Worker::Render(const TaskAssignment& task, const std::atomic<bool>& cancel) {
    // Pieces of one row and a few tens of thousands of samples: small enough that a cancel
    // stops the work within a fraction of a second (RenderTile checks between rows), and exact
    // sums make any split of the tile give the same bits.
    constexpr uint64_t kSamplesPerPiece = 1 << 16;
    const PixelRect& rect = task.task.rect;
    const uint64_t step = std::max<uint64_t>(1, kSamplesPerPiece / uint64_t(rect.width));
    const SampleOptions options{task.spec.clamp, task.spec.aovs, task.spec.sampler};
    const PixelMask active = task.task.active();
    TileSums tile(rect, options.aovs);
    std::mutex stats_mutex;
    arena_.execute([&] {
        tbb::parallel_for(
            tbb::blocked_range<int>(rect.y0, rect.y0 + rect.height, 1),
            [&](const tbb::blocked_range<int>& rows) {
                for (int y = rows.begin(); y != rows.end(); ++y) {
                    const PixelRect row_rect{rect.x0, y, rect.width, 1};
                    TileSums row(row_rect, options.aovs);
                    for (uint64_t s = task.task.sample_begin; s < task.task.sample_end && !cancel;
                         s += step) {
                        row += RenderTile(
                            *loaded_.camera, *loaded_.tracer, row_rect, task.spec.seed, s,
                            std::min(s + step, task.task.sample_end), options, &cancel, &active);
                    }
                    std::copy(row.pixels.begin(), row.pixels.end(), &tile.at(rect.x0, y));
                    if (options.aovs != 0) {
                        std::copy(row.aov_pixels.begin(), row.aov_pixels.end(),
                                  tile.aov_pixels.begin() + ptrdiff_t(tile.Index(rect.x0, y)));
                    }
                    std::lock_guard<std::mutex> lock(stats_mutex);
                    tile.stats += row.stats;
                }
            });
    });
    return tile;
}

absl::Status Worker::RenderSplat(const TaskAssignment& task, const std::atomic<bool>& cancel,
                                 ServerConnection::TaskResult& result, RenderStats& stats,
                                 SplatList* frame_splats) {
    if (!loaded_.frame) {
        // Cached per job (loaded_.job_id), through the conversions local mode uses, so one job's
        // settings give local mode's kernel.
        const JobSpec& spec = task.spec;
        absl::StatusOr<std::unique_ptr<SplatRenderer>> made = MakeSplatRenderer(
            MethodOf(spec), *loaded_.embree, *loaded_.camera, SplatRenderSettingsOf(spec));
        if (!made.ok()) return made.status();
        loaded_.frame = std::move(*made);
    }
    const SplatWork work{task.task.rect, task.task.sample_begin, task.task.sample_end,
                         task.path_begin, task.path_end};
    TileSums camera(task.task.rect, 0);
    SplatList own(loaded_.camera->width(), loaded_.camera->height());
    if (frame_splats && frame_splats->width() == 0) *frame_splats = own;
    SplatList& splats = frame_splats ? *frame_splats : own;
    // The renderer runs tbb inside: in this worker's arena, so --threads bounds it.
    arena_.execute([&] { loaded_.frame->Render(work, camera, splats, &cancel); });
    if (cancel) return absl::CancelledError("splat task cancelled");
    stats = camera.stats;
    result.bytes = EncodeTileSums(camera);
    if (frame_splats) return absl::OkStatus();
    result.splats = EncodeSplatList(splats);
    const size_t bytes = result.bytes.size() + result.splats->size();
    // Above the bound the coordinator would refuse the message: said here, in its terms.
    if (bytes > size_t(kMaxTaskResultBytes) - 4096) {
        return absl::FailedPreconditionError(absl::StrCat(
            "the result of job ", task.job_id, " task ", task.task.index, " is ", bytes,
            " bytes, above the coordinator's bound of ", kMaxTaskResultBytes,
            " (lf::kMaxTaskResultBytes): render with more --passes (fewer light paths a task) "
            "or a finite --max-depth"));
    }
    return absl::OkStatus();
}

void Worker::SendResult(const TaskAssignment& task, ServerConnection::TaskResult result,
                        double seconds) {
    std::unique_lock<std::mutex> lock(send_mutex_);
    send_cv_.wait(lock, [&] { return !pending_ && !sending_; });
    pending_ = PendingResult{task, std::move(result), seconds};
    send_cv_.notify_all();
}

void Worker::FlushSends() {
    std::unique_lock<std::mutex> lock(send_mutex_);
    send_cv_.wait(lock, [&] { return !pending_ && !sending_; });
}

void Worker::SenderLoop() {
    // It sends one task's result while the next task runs: its lines are neither's log.
    TaskLogSink::IgnoreThisThread();
    std::unique_lock<std::mutex> lock(send_mutex_);
    while (true) {
        send_cv_.wait(lock, [&] { return pending_ || sender_stop_; });
        if (!pending_) return;  // stopping, and everything handed over is sent
        const PendingResult sending = std::move(*pending_);
        pending_.reset();
        sending_ = true;
        lock.unlock();
        const TaskAssignment& task = sending.task;
        const absl::Status sent = server_.Complete(task.lease_id, sending.result, sending.seconds);
        if (sent.ok()) {
            Log()->debug("job={} task={} done in {:.2f} s", task.job_id, task.task.index,
                         sending.seconds);
        } else {
            Log()->warn("job={} task={} result not taken: {}", task.job_id, task.task.index,
                        std::string(sent.message()));
        }
        lock.lock();
        sending_ = false;
        send_cv_.notify_all();
    }
}

}  // namespace lf
