#include "lf/server/farm.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <set>

#include "absl/strings/str_cat.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/plural.h"
#include "lf/core/radiosity_codec.h"
#include "lf/core/splat_codec.h"
#include "lf/core/tile_codec.h"
#include "lf/job/digest.h"
#include "lf/job/method_registry.h"
#include "lf/job/plan.h"
#include "lf/job/render_metadata.h"

namespace lf {

namespace fs = std::filesystem;

namespace {

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("farm"); }

// A name no other writer in this process uses at the same time.
std::string UniqueSuffix() {
    static std::atomic<uint64_t> counter{0};
    return absl::StrCat(::getpid(), "-", ++counter);
}

// The scheduler's options with each job's tiles in a file under the data folder's scratch/.
SchedulerOptions WithTileFiles(SchedulerOptions options, const std::string& data_dir) {
    options.tile_stores = [dir = data_dir + "/scratch"](std::vector<PixelRect> tiles,
                                                        uint32_t aovs) {
        return MakeFileTileStore(dir, std::move(tiles), aovs);
    };
    return options;
}

}  // namespace

absl::StatusOr<std::unique_ptr<Farm>> Farm::Open(const FarmOptions& options) {
    std::error_code ec;
    for (const char* sub : {"results", "previews", "scratch"}) {
        fs::create_directories(fs::path(options.data_dir) / sub, ec);
        if (ec) return absl::InternalError(options.data_dir + "/" + sub + ": " + ec.message());
    }
    absl::StatusOr<std::unique_ptr<DirLock>> lock =
        DirLock::Acquire(options.data_dir, {"data folder", "lightfarm-server", "--data-dir"});
    if (!lock.ok()) return lock.status();
    absl::StatusOr<std::unique_ptr<BlobStore>> blobs = BlobStore::Open(options.data_dir + "/blobs");
    if (!blobs.ok()) return blobs.status();
    absl::StatusOr<std::unique_ptr<SqliteJobStore>> store =
        SqliteJobStore::Open(options.data_dir + "/jobs.db");
    if (!store.ok()) return store.status();
    absl::StatusOr<std::unique_ptr<TaskLogStore>> logs =
        TaskLogStore::Open(options.data_dir + "/logs.db", options.task_logs);
    if (!logs.ok()) return logs.status();
    std::unique_ptr<Farm> farm(
        new Farm(options, std::move(*blobs), std::move(*store), std::move(*logs)));
    farm->lock_ = std::move(*lock);
    if (!options.notify_url.empty()) {
        absl::StatusOr<std::unique_ptr<JobNotifier>> notifier =
            JobNotifier::Start(options.notify_url, options.notify);
        if (!notifier.ok()) return notifier.status();
        farm->notifier_ = std::move(*notifier);
    }
    absl::StatusOr<std::unique_ptr<WorkerStateStore>> worker_states =
        WorkerStateStore::Open(options.data_dir + "/workers.db");
    if (!worker_states.ok()) return worker_states.status();
    farm->worker_states_ = std::move(*worker_states);
    absl::StatusOr<std::map<std::string, WorkerControl>> controls = farm->worker_states_->List();
    if (!controls.ok()) return controls.status();
    for (const auto& [name, control] : *controls) farm->scheduler_.SetWorkerControl(name, control);
    farm->SweepTemporaryFiles();
    absl::StatusOr<std::vector<Scheduler::JobRun>> rendered = farm->scheduler_.Recover();
    if (!rendered.ok()) return rendered.status();
    // Frames complete before the restart whose EXR was not recorded, of shots still running.
    for (const auto& [run, frame] : farm->scheduler_.UnwrittenFrames()) {
        if (std::find(rendered->begin(), rendered->end(), run) == rendered->end()) {
            farm->WriteFrame(run, frame);
        }
    }
    for (const Scheduler::JobRun& run : *rendered) (void)farm->FinishJob(run);
    if (absl::StatusOr<int> expired = farm->DeleteExpired(absl::Now()); !expired.ok()) {
        return expired.status();
    }
    return farm;
}

Farm::Farm(const FarmOptions& options, std::unique_ptr<BlobStore> blobs,
           std::unique_ptr<SqliteJobStore> store, std::unique_ptr<TaskLogStore> logs)
    : options_(options),
      blobs_(std::move(blobs)),
      store_(std::move(store)),
      logs_(std::move(logs)),
      scheduler_(WithTileFiles(options.scheduler, options.data_dir), *store_) {
    scheduler_.OnTasksEnded([this](const JobRecord& ended, std::vector<TaskStatus> tasks) {
        // The job has ended either way: `lightfarm tasks` then lists none of its tasks.
        if (absl::Status s = logs_->RecordTasks(ended.id, tasks); !s.ok()) {
            Log()->error("job={} tasks not recorded: {}", ended.id, std::string(s.message()));
        }
        // The record it ended with: read again, a job requeued meanwhile would be queued.
        if (notifier_) notifier_->JobEnded(ended);
    });
}

absl::Status Farm::CheckSceneSize(uint64_t bytes) const {
    if (bytes <= options_.limits.max_scene_bytes) return absl::OkStatus();
    return absl::ResourceExhaustedError(
        absl::StrCat("the scene and its files are ", bytes, " bytes, above this server's limit of ",
                     options_.limits.max_scene_bytes, " (lightfarm-server --max-scene-mb)"));
}

absl::StatusOr<std::unique_ptr<BlobStore::Upload>> Farm::StartUpload(const std::string& hash,
                                                                     uint64_t size,
                                                                     uint64_t offset) {
    if (absl::Status s = CheckSceneSize(size); !s.ok()) return s;
    return blobs_->StartUpload(hash, size, offset);
}

absl::StatusOr<std::string> Farm::Submit(JobSpec spec) {
    // The CLI's limits (lf/job/job_spec.h): a bad job is refused here rather than failing, or
    // running without end, on every worker.
    if (absl::Status s = CheckJobSettings(spec); !s.ok()) return s;
    if (spec.name.size() > kMaxJobNameBytes) {
        return absl::InvalidArgumentError(absl::StrCat(
            "job name of ", spec.name.size(), " bytes is above the limit of ", kMaxJobNameBytes));
    }
    if (spec.request_id.size() > kMaxRequestIdBytes) {
        return absl::InvalidArgumentError(absl::StrCat("request id of ", spec.request_id.size(),
                                                       " bytes is above the limit of ",
                                                       kMaxRequestIdBytes));
    }
    // A request id is its submitter's: another owner's same id is another request, never a way
    // to learn that owner's job id or to have one's own submission dropped. Token names hold
    // no '/'.
    if (!spec.request_id.empty()) spec.request_id = absl::StrCat(spec.owner, "/", spec.request_id);
    std::vector<const BlobRef*> refs = {&spec.scene};
    for (const BlobRef& f : spec.files) refs.push_back(&f);
    uint64_t scene_bytes = 0;
    for (const BlobRef* ref : refs) scene_bytes += ref->size;
    if (absl::Status s = CheckSceneSize(scene_bytes); !s.ok()) return s;
    if (spec.plan.spp > options_.limits.max_spp) {
        return absl::ResourceExhaustedError(
            absl::StrCat(spec.plan.spp, " samples per pixel is above this server's limit of ",
                         options_.limits.max_spp, " (lightfarm-server --max-spp)"));
    }
    std::shared_lock<std::shared_mutex> blobs_in_use(blob_users_);
    for (const BlobRef* ref : refs) {
        if (absl::Status s = CheckScenePath(ref->path); !s.ok()) return s;
        if (!blobs_->Has(ref->hash)) {
            return absl::FailedPreconditionError(
                absl::StrCat(ref->path, ": blob ", ref->hash, " was not uploaded"));
        }
        // The size limit above was checked on the declared sizes.
        if (absl::StatusOr<uint64_t> size = blobs_->SizeOf(ref->hash); !size.ok()) {
            return size.status();
        } else if (*size != ref->size) {
            return absl::InvalidArgumentError(absl::StrCat(ref->path, ": declared as ", ref->size,
                                                           " bytes, its blob holds ", *size));
        }
    }
    if (IsAdaptive(spec.adaptive) && spec.adaptive.max_spp > options_.limits.max_spp) {
        return absl::ResourceExhaustedError(absl::StrCat(
            "adaptive sampling up to ", spec.adaptive.max_spp,
            " samples per pixel is above this server's limit of ", options_.limits.max_spp,
            " (lightfarm-server --max-spp); lower --max-spp"));
    }
    absl::StatusOr<Scene> scene = LoadSceneFromBlobs(
        spec.scene, spec.files, [&](const std::string& hash) { return blobs_->PathOf(hash); },
        nullptr, spec.scene_options);
    // The service logs the refusal with its caller.
    if (!scene.ok()) return absl::InvalidArgumentError(scene.status().message());
    // Refused here, once, rather than failing on every worker.
    if (absl::Status s = CheckMethodTakesScene(MethodOf(spec), *scene); !s.ok()) return s;
    // A shot's scene must pose: malformed animation is refused as `render --frames` refuses it.
    if (spec.shot.frames) {
        if (absl::Status s = PoseSceneAtFrame(spec.shot.frames->first, spec.shot, *scene);
            !s.ok()) {
            return absl::InvalidArgumentError(s.message());
        }
    }
    const int side = options_.limits.max_resolution;
    if (scene->camera.width > side || scene->camera.height > side) {
        return absl::ResourceExhaustedError(absl::StrCat("resolution ", scene->camera.width, "x",
                                                         scene->camera.height,
                                                         " is above this server's limit of ", side,
                                                         " pixels per side "
                                                         "(lightfarm-server --max-resolution)"));
    }
    spec.plan.width = scene->camera.width;
    spec.plan.height = scene->camera.height;
    spec.scene_hash = scene->content_hash;
    // The filter the scene resolves to (its camera's, or --filter's), kept with the job for the
    // EXR header, which is written without loading the scene again.
    spec.scene_options.filter = scene->camera.filter;
    return scheduler_.Submit(spec);
}

absl::Status Farm::RefuseUndecodable(const std::string& lease_id, const std::string& worker,
                                     const absl::Status& why) {
    const std::string reason = absl::StrCat("undecodable result: ", why.message());
    // Named as the scheduler's own refusals name them, before the failure may end the job.
    const std::optional<Scheduler::LeaseHolder> holder = scheduler_.HolderOf(lease_id, worker);
    const std::string task =
        holder ? absl::StrCat("job=", holder->job_id, " task=", holder->task, " ") : "";
    scheduler_.Fail(lease_id, worker, reason, FailureKind::kTaskError).IgnoreError();
    return absl::InvalidArgumentError(
        absl::StrCat(task, "lease ", lease_id, " from ", worker, ": ", reason));
}

absl::Status Farm::Complete(const std::string& lease_id, const std::string& worker,
                            std::string_view tile_sums, std::optional<RadiosityFigures> radiosity,
                            std::optional<std::string_view> splats, std::optional<int> frame,
                            const std::vector<ResultPart>& parts, const TaskTimes& times) {
    // As many parts as the task has, checked before any is decoded: a worker's message of
    // millions of empty parts costs no decoding.
    const std::optional<Scheduler::LeaseHolder> holder = scheduler_.HolderOf(lease_id, worker);
    // Not a lease of a running job (it ended, or the id is made up): the scheduler says so.
    if (!holder) return scheduler_.Complete(lease_id, worker, TaskResult{}).status();
    if (const size_t want = holder->parts; parts.size() != want) {
        return RefuseUndecodable(lease_id, worker,
                                 absl::InvalidArgumentError(absl::StrCat(
                                     parts.size(), " parts in the result of a task of ", want,
                                     want == 1 ? " part" : " parts")));
    }
    // A chunk's parts, or the one result; kept in place while the result points at them.
    std::vector<ResultPart> wire = parts;
    if (parts.empty()) wire.push_back({frame.value_or(0), tile_sums, splats, times});
    std::vector<TileSums> sums;
    std::vector<std::optional<SplatList>> lists;
    sums.reserve(wire.size());
    lists.reserve(wire.size());
    for (const ResultPart& part : wire) {
        absl::StatusOr<TileSums> decoded = DecodeTileSums(part.tile_sums);
        if (!decoded.ok()) return RefuseUndecodable(lease_id, worker, decoded.status());
        sums.push_back(std::move(*decoded));
        // Checked whole before anything is allocated (lf::DecodeSplatList); its frame and the
        // camera part are the scheduler's to check against the task.
        lists.emplace_back();
        if (part.splats) {
            absl::StatusOr<SplatList> list = DecodeSplatList(*part.splats);
            if (!list.ok()) return RefuseUndecodable(lease_id, worker, list.status());
            lists.back() = std::move(*list);
        }
    }
    std::vector<TaskResult> results;
    for (size_t i = 0; i < wire.size(); ++i) {
        results.push_back({.sums = &sums[i],
                           .encoded_sums = wire[i].tile_sums,
                           .splats = lists[i] ? &*lists[i] : nullptr,
                           .frame = parts.empty() ? frame : std::optional<int>(wire[i].frame),
                           .times = wire[i].times});
    }
    TaskResult chunk{.parts = std::move(results), .times = times};
    const TaskResult& result = parts.empty() ? chunk.parts.front() : chunk;
    absl::StatusOr<Scheduler::Completion> done = scheduler_.Complete(lease_id, worker, result);
    if (!done.ok()) {
        // A chunk refused half way keeps the parts merged before the refusal: the frames they
        // completed are written now, so that a shot cancelled before the retry still has them.
        if (!parts.empty()) {
            for (const auto& [run, f] : scheduler_.UnwrittenFrames()) {
                if (run.job_id == holder->job_id) WriteFrame(run, f);
            }
        }
        return done.status();
    }
    const Scheduler::JobRun run{done->job_id, done->run};
    if (radiosity) {
        std::lock_guard<std::mutex> lock(radiosity_mutex_);
        radiosity_[run] = *radiosity;
    }
    for (int f : done->frames_completed) WriteFrame(run, f);
    // The job's image is written while the last result's record is made durable: a restart
    // before both finds the task not done and renders it again.
    if (done->job_rendered) return FinishJob(run, &*done);
    return scheduler_.AwaitRecorded(*done);
}

std::string Farm::FramePathOf(const std::string& dir, const std::string& job_id, int frame) const {
    return absl::StrCat(options_.data_dir, "/", dir, "/", job_id, ".frame", frame, ".exr");
}

void Farm::WriteFrame(const Scheduler::JobRun& run, int frame) {
    const std::string path = FramePathOf("results", run.job_id, frame);
    // Held until the frame is recorded: a run queued meanwhile writes this path only after.
    std::lock_guard<std::mutex> lock(image_mutex_);
    absl::StatusOr<Scheduler::JobImage> snapshot = scheduler_.FrameSnapshot(run.job_id, frame);
    if (absl::IsFailedPrecondition(snapshot.status())) return;  // cancelled meanwhile
    if (snapshot.ok()) {
        if (snapshot->run != run.run) return;  // and queued again
        // Written by another result's thread since this one read UnwrittenFrames: its file is
        // recorded, and must not be rewritten (nor removed, were the job to end meanwhile).
        for (const FrameProgress& f : snapshot->record.frames) {
            if (f.frame == frame && !f.result_path.empty()) return;
        }
    }
    const absl::Status written =
        snapshot.ok() ? WriteImage(*snapshot, true, path) : snapshot.status();
    const bool recorded = scheduler_.FrameWritten(
        run, frame,
        written.ok() ? absl::StatusOr<std::string>(path) : absl::StatusOr<std::string>(written));
    // Ended during the write: the frame is not this job's any more (a run queued again renders
    // and writes it itself, and `requeue --frames` removed it before the write put it back).
    if (!recorded && written.ok()) {
        std::error_code ignored;
        fs::remove(path, ignored);
    }
}

absl::Status Farm::CompleteSweep(const std::string& lease_id, const std::string& worker,
                                 std::string_view sweep_result, const TaskTimes& times,
                                 const std::optional<RadiosityFigures>& links) {
    absl::StatusOr<std::vector<SweepChunkResult>> results =
        DecodeSweepResults(sweep_result, size_t(kMaxSweepTasks));
    if (!results.ok()) return RefuseUndecodable(lease_id, worker, results.status());
    absl::StatusOr<Scheduler::Completion> done =
        scheduler_.Complete(lease_id, worker, TaskResult{.sweeps = *results, .times = times});
    if (!done.ok()) return done.status();
    // A chunk's links come with its sweep-0 task, which is of that chunk alone (a chunk may
    // have no links: its share of the solver's bytes still counts).
    if (links && results->size() == 1 && results->front().sweep == 0) {
        std::lock_guard<std::mutex> lock(radiosity_mutex_);
        sweep_links_[{done->job_id, done->run}][results->front().chunk] = *links;
    }
    if (done->sweep && done->sweep->converged) {
        std::lock_guard<std::mutex> lock(radiosity_mutex_);
        sweep_solves_[{done->job_id, done->run}] = {done->sweep->iterations, done->sweep->residual};
    }
    if (done->sweep) {
        std::string encoded = EncodeRadiosity(done->sweep->radiosity);
        // A sweep's input is soft state, like the sweep's results (a restart solves again): it
        // goes with the leases of the next sweep, one a worker. The solution goes to every
        // display tile's lease, of which a worker reads one: it is a blob each worker fetches
        // once.
        if (!done->sweep->converged &&
            encoded.size() <= std::min(options_.inline_radiosity_bytes, kMaxInlineRadiosityBytes)) {
            auto bytes = std::make_shared<const std::string>(std::move(encoded));
            scheduler_.Publish(done->job_id, false, Sha256Hex(*bytes), bytes);
        } else {
            scheduler_.Publish(done->job_id, done->sweep->converged, blobs_->Put(encoded));
        }
    }
    return absl::OkStatus();
}

absl::Status Farm::WriteSnapshot(const std::string& job_id, bool complete, const std::string& path,
                                 std::optional<uint64_t> run) {
    std::lock_guard<std::mutex> lock(image_mutex_);
    absl::StatusOr<Scheduler::JobImage> snapshot = scheduler_.Snapshot(job_id);
    if (!snapshot.ok()) return snapshot.status();
    if (run && snapshot->run != *run) {
        return absl::FailedPreconditionError(
            absl::StrCat("job ", job_id, " was cancelled and queued again"));
    }
    return WriteImage(*snapshot, complete, path);
}

absl::Status Farm::FinishJob(const Scheduler::JobRun& rendered, const Scheduler::Completion* last) {
    const std::string& job_id = rendered.job_id;
    // The job ends only once every result is recorded: one that is not fails it (AwaitRecorded).
    const auto recorded = [&] { return last ? scheduler_.AwaitRecorded(*last) : absl::OkStatus(); };
    absl::StatusOr<JobRecord> job = scheduler_.Get(job_id);
    if (job.ok() && job->spec.shot.frames) {
        // Its frames are its result, each written as it completed; those a restart or a time
        // limit completed since are written now.
        for (const auto& [run, frame] : scheduler_.UnwrittenFrames()) {
            if (run == rendered) WriteFrame(run, frame);
        }
        job = scheduler_.Get(job_id);
        if (job.ok() && IsFinal(job->state)) return recorded();  // a frame's write failed it
        if (absl::Status s = recorded(); !s.ok()) return s;
        scheduler_.Finish(rendered,
                          job.ok() && !job->frames.empty()
                              ? absl::StatusOr<std::string>(job->frames.back().result_path)
                              : absl::StatusOr<std::string>(job.status()));
        return absl::OkStatus();
    }
    const std::string path = options_.data_dir + "/results/" + job_id + ".exr";
    const absl::Status written = WriteSnapshot(job_id, true, path, rendered.run);
    {
        // This run's figures, and those of runs cancelled before it; a later run keeps its own.
        std::lock_guard<std::mutex> lock(radiosity_mutex_);
        const auto up_to_this_run = [&](auto& figures) {
            figures.erase(figures.lower_bound({job_id, 0}),
                          figures.upper_bound({job_id, rendered.run}));
        };
        up_to_this_run(radiosity_);
        up_to_this_run(sweep_solves_);
        up_to_this_run(sweep_links_);
    }
    // Cancelled meanwhile (and perhaps queued again: that run writes its own image).
    if (absl::IsFailedPrecondition(written)) return recorded();
    if (absl::Status s = recorded(); !s.ok()) {
        // Nothing may serve the image of a failed job; a run queued again since the write may
        // have written its own there (under image_mutex_), and may have succeeded with it.
        std::lock_guard<std::mutex> lock(image_mutex_);
        const std::optional<uint64_t> now = scheduler_.RunOf(job_id);
        const absl::StatusOr<JobRecord> ended = scheduler_.Get(job_id);
        const bool later_succeeded = ended.ok() && ended->state == JobState::kSucceeded;
        std::error_code ignored;
        if (written.ok() && (now ? *now == rendered.run : !later_succeeded)) {
            fs::remove(path, ignored);
        }
        return s;
    }
    scheduler_.Finish(rendered, written.ok() ? absl::StatusOr<std::string>(path)
                                             : absl::StatusOr<std::string>(written));
    return absl::OkStatus();
}

void Farm::CheckTimers() {
    scheduler_.ExpireLeases();
    for (const Scheduler::JobRun& run : scheduler_.EnforceTimeLimits()) (void)FinishJob(run);
}

absl::Status Farm::WriteImage(const Scheduler::JobImage& snapshot, bool complete,
                              const std::string& path) {
    const JobRecord& job = snapshot.record;
    RenderOutcome outcome;
    outcome.seconds = job.started == absl::InfinitePast()
                          ? 0.0
                          : absl::ToDoubleSeconds(absl::Now() - job.started);
    outcome.stats = job.stats;
    outcome.adaptive = snapshot.adaptive;
    {
        std::lock_guard<std::mutex> lock(radiosity_mutex_);
        const Scheduler::JobRun run{job.id, snapshot.run};
        if (auto it = radiosity_.find(run); it != radiosity_.end()) {
            outcome.radiosity = it->second;
            // The display tiles' workers read the farm's solution: the solve's figures are ours.
            if (auto solve = sweep_solves_.find(run); solve != sweep_solves_.end()) {
                outcome.radiosity->iterations = solve->second.iterations;
                outcome.radiosity->residual = solve->second.residual;
            }
            if (auto links = sweep_links_.find(run); links != sweep_links_.end()) {
                RadiosityFigures& r = *outcome.radiosity;
                for (const auto& [chunk, f] : links->second) {
                    r.links += f.links;
                    r.link_bytes += f.link_bytes;
                    r.solver_bytes += f.solver_bytes;
                }
                r.links_per_side = double(r.links) / std::max<double>(1, double(r.unknowns));
            }
        }
    }
    absl::StatusOr<RenderDescription> description =
        DescribeRender(MetadataOf(job.spec, outcome), snapshot.image, complete);
    if (!description.ok()) return description.status();
    const ExrAttributes& attributes = description->attributes;
    // Renamed into place so a reader never sees half a file, and durable before the job is
    // recorded as succeeded.
    const std::string temp = path + ".tmp-" + UniqueSuffix();
    if (absl::Status s = WriteExr(temp, snapshot.image, attributes); !s.ok()) return s;
    return RenameDurably(temp, path);
}

absl::StatusOr<std::string> Farm::ResultFile(const std::string& job_id, bool preview,
                                             std::optional<int> frame) {
    absl::StatusOr<JobRecord> job = scheduler_.Get(job_id);
    if (!job.ok()) return job.status();
    if (frame) {
        if (absl::Status s = CheckRendersFrame(*job, *frame); !s.ok()) return s;
        if (const FrameProgress* f = FrameOf(*job, *frame); f && !f->result_path.empty()) {
            return f->result_path;
        }
        if (!preview || IsFinal(job->state)) {
            return absl::FailedPreconditionError(absl::StrCat(
                "job ", job_id, " frame ", *frame, " is not finished (job ",
                JobStateName(job->state), ", ", job->frames_done(), "/",
                job->spec.shot.frames->count(), " frames done): no result",
                IsFinal(job->state) ? "" : " yet; --preview fetches what is merged so far"));
        }
        const std::string path = FramePathOf("previews", job_id, *frame);
        std::lock_guard<std::mutex> lock(image_mutex_);
        absl::StatusOr<Scheduler::JobImage> snapshot = scheduler_.FrameSnapshot(job_id, *frame);
        if (!snapshot.ok()) return snapshot.status();
        if (absl::Status s = WriteImage(*snapshot, false, path); !s.ok()) return s;
        return path;
    }
    if (job->spec.shot.frames && !preview) {
        return absl::FailedPreconditionError(absl::StrCat(
            "job ", job_id, " is a shot of frames ", FrameRangeText(*job->spec.shot.frames), " (",
            job->frames_done(), " done): fetch its frames (lightfarm fetch JOB -o out_####.exr)"));
    }
    if (IsFinal(job->state)) {
        std::lock_guard<std::mutex> lock(image_mutex_);
        previewed_.erase(job_id);
    }
    if (job->state == JobState::kSucceeded) return job->result_path;
    if (!preview || IsFinal(job->state)) {
        return absl::FailedPreconditionError(absl::StrCat(
            "job ", job_id, " is ", JobStateName(job->state), " (", job->tasks_done, "/",
            job->tasks_total, " tasks done): no result",
            IsFinal(job->state) ? "" : " yet; --preview fetches what is merged so far"));
    }
    const std::string path = options_.data_dir + "/previews/" + job_id + ".exr";
    {
        std::lock_guard<std::mutex> lock(image_mutex_);
        auto it = previewed_.find(job_id);
        if (it != previewed_.end() && it->second == job->tasks_done) return path;
    }
    if (absl::Status s = WriteSnapshot(job_id, false, path); !s.ok()) {
        // The job ended since it was read: its last task merged meanwhile. Its result, once
        // written, is the preview asked for.
        absl::StatusOr<JobRecord> now = scheduler_.Get(job_id);
        if (absl::IsFailedPrecondition(s) && now.ok() && IsFinal(now->state)) {
            return ResultFile(job_id, preview);
        }
        return s;
    }
    std::lock_guard<std::mutex> lock(image_mutex_);
    previewed_[job_id] = job->tasks_done;
    return path;
}

}  // namespace lf

namespace lf {

void Farm::RemoveJobFiles(const std::string& job_id) {
    for (const char* sub : {"results", "previews"}) {
        std::error_code ignored;  // a job without such a file
        fs::remove(fs::path(options_.data_dir) / sub / (job_id + ".exr"), ignored);
        // A shot's frames: JOB.frame<N>.exr (job ids are random hex, no prefix of another's).
        const std::string prefix = job_id + ".frame";
        std::vector<fs::path> frames;
        for (fs::directory_iterator it(fs::path(options_.data_dir) / sub, ignored), end;
             !ignored && it != end; it.increment(ignored)) {
            if (it->path().filename().string().rfind(prefix, 0) == 0) frames.push_back(it->path());
        }
        for (const fs::path& frame : frames) fs::remove(frame, ignored);
    }
}

absl::Status Farm::DeleteJob(const std::string& job_id) {
    std::lock_guard<std::mutex> one_change(ended_job_changes_);
    absl::StatusOr<JobRecord> job = scheduler_.Get(job_id);
    if (!job.ok()) return job.status();
    if (!IsFinal(job->state)) {
        return absl::FailedPreconditionError(absl::StrCat(
            "job ", job_id, " is ", JobStateName(job->state), ": cancel it before deleting it"));
    }
    if (absl::Status s = store_->Delete(job_id); !s.ok()) return s;
    RemoveJobFiles(job_id);
    RemoveJobLogs({job_id});
    // The job is gone either way: a blob left now goes at the next hourly sweep.
    if (absl::StatusOr<BlobStore::Removed> removed = RemoveUnusedBlobs(absl::Now());
        !removed.ok()) {
        Log()->error("job={} deleted; its blobs stay: {}", job_id,
                     std::string(removed.status().message()));
    }
    return absl::OkStatus();
}

absl::StatusOr<BlobStore::Removed> Farm::RemoveUnusedBlobs(absl::Time now) {
    std::unique_lock<std::shared_mutex> no_submission(blob_users_);
    std::set<std::string> used = scheduler_.BlobsInUse();
    absl::StatusOr<std::vector<JobRecord>> stored = store_->List();
    if (!stored.ok()) return stored.status();
    for (const JobRecord& job : *stored) {
        used.insert(job.spec.scene.hash);
        for (const BlobRef& file : job.spec.files) used.insert(file.hash);
    }
    const BlobStore::Removed removed =
        blobs_->RemoveUnused(used, now - kUnusedBlobGrace, now - kPartialUploadLifetime);
    if (removed.blobs > 0 || removed.partials > 0) {
        Log()->info("removed {} no job uses ({} bytes) and {}", Plural(removed.blobs, "blob"),
                    removed.blob_bytes, Plural(removed.partials, "stale partial upload"));
    }
    return removed;
}

absl::StatusOr<int> Farm::DeleteExpired(absl::Time now) {
    // In pages, so that a long-idle server does not load every expired job at once.
    constexpr size_t kPage = 1000;
    int deleted = 0;
    while (options_.retention > absl::ZeroDuration()) {
        std::lock_guard<std::mutex> one_change(ended_job_changes_);
        absl::StatusOr<std::vector<JobRecord>> expired =
            store_->List({.limit = kPage, .ended_before = now - options_.retention});
        if (!expired.ok()) return expired.status();
        if (expired->empty()) break;
        uint64_t ticket = 0;
        for (const JobRecord& job : *expired) ticket = store_->QueueDelete(job.id);
        if (absl::Status s = store_->WaitDurable(ticket); !s.ok()) return s;
        std::vector<std::string> ids;
        for (const JobRecord& job : *expired) {
            RemoveJobFiles(job.id);
            ids.push_back(job.id);
        }
        RemoveJobLogs(ids);
        deleted += int(expired->size());
    }
    if (deleted > 0) {
        Log()->info("deleted {} that ended more than {} ago", Plural(deleted, "job"),
                    absl::FormatDuration(options_.retention));
    }
    if (absl::StatusOr<BlobStore::Removed> removed = RemoveUnusedBlobs(now); !removed.ok()) {
        return removed.status();
    }
    return deleted;
}

void Farm::RemoveJobLogs(const std::vector<std::string>& job_ids) {
    // The jobs are gone either way; lines left behind are found by no one.
    if (absl::Status s = logs_->Delete(job_ids); !s.ok()) {
        Log()->error("the task logs of {} deleted jobs stay in logs.db: {}", job_ids.size(),
                     std::string(s.message()));
    }
}

absl::StatusOr<std::vector<TaskStatus>> Farm::Tasks(const std::string& job_id) {
    std::optional<std::vector<TaskStatus>> tasks = scheduler_.Tasks(job_id);
    if (!tasks) {
        absl::StatusOr<JobRecord> job = scheduler_.Get(job_id);
        if (!job.ok()) return job.status();
        // Ended: as recorded when it ended (a job ended just now may not be yet).
        absl::StatusOr<std::vector<TaskStatus>> recorded = logs_->Tasks(job_id);
        if (!recorded.ok()) return recorded.status();
        tasks = std::move(*recorded);
    }
    absl::StatusOr<std::map<int, int>> counts = logs_->LineCounts(job_id);
    if (!counts.ok()) return counts.status();
    for (TaskStatus& task : *tasks) {
        if (auto it = counts->find(task.index); it != counts->end()) task.log_lines = it->second;
    }
    return *tasks;
}

absl::StatusOr<TaskLogPage> Farm::TaskLogs(const std::string& job_id, std::optional<int> task,
                                           int64_t after_seq, int max_lines) {
    // Whether the job has ended is read before its lines: the last lines of its tasks are kept
    // before their results are taken (TakeTaskLog), so none follow an ended job's page.
    absl::StatusOr<JobRecord> job = scheduler_.Get(job_id);
    if (!job.ok()) return job.status();
    if (task && (*task < 0 || *task >= job->tasks_total)) {
        return absl::NotFoundError(absl::StrCat(
            "job ", job_id, " has no task ", *task, ": it has ", Plural(job->tasks_total, "task"),
            job->tasks_total > 0 ? absl::StrCat(", 0 to ", job->tasks_total - 1) : ""));
    }
    const int page_size = max_lines <= 0 ? kMaxTaskLogPage : std::min(max_lines, kMaxTaskLogPage);
    absl::StatusOr<TaskLogPage> page = logs_->Read(job_id, task, after_seq, page_size);
    if (!page.ok()) return page.status();
    page->job_ended = IsFinal(job->state) && int(page->lines.size()) < page_size;
    return page;
}

absl::Status Farm::TakeTaskLog(const std::string& lease_id, const std::string& worker,
                               std::vector<TaskLogLine> lines) {
    if (lines.empty()) return absl::OkStatus();
    const std::optional<Scheduler::LeaseHolder> holder = scheduler_.HolderOf(lease_id, worker);
    // A late heartbeat's lines for a lease that ended are not kept: the attempt is over.
    if (!holder || !holder->current) return absl::OkStatus();
    return logs_->Append(holder->job_id, holder->task, holder->attempt, holder->worker,
                         std::move(lines));
}

void Farm::SweepTemporaryFiles() {
    // Nothing in scratch/ or previews/ outlives the request that wrote it, and a result's
    // temporary file is renamed or removed before its job is recorded.
    int removed = blobs_->SweepUnfinishedUploads();
    for (const char* sub : {"scratch", "previews", "results"}) {
        std::error_code ec;
        for (const fs::directory_entry& entry :
             fs::directory_iterator(fs::path(options_.data_dir) / sub, ec)) {
            if (sub == std::string_view("results") &&
                entry.path().filename().string().find(".tmp-") == std::string::npos) {
                continue;
            }
            std::error_code ignored;
            removed += fs::remove_all(entry.path(), ignored) > 0;
        }
    }
    if (removed > 0) Log()->info("removed {} temporary files left by an earlier run", removed);
}

}  // namespace lf

namespace lf {

absl::StatusOr<std::vector<WorkerStatus>> Farm::SetWorkerState(const std::string& name_or_id,
                                                               WorkerControl control) {
    const std::optional<std::string> key = scheduler_.WorkerKey(name_or_id);
    if (!key) {
        return absl::NotFoundError(
            absl::StrCat("no worker named ", LogSafe(name_or_id, 128),
                         " nor with that id (lightfarm workers lists them)"));
    }
    {
        // The store and the scheduler in the same order for every caller: two concurrent
        // changes of one worker leave both holding the later one.
        std::lock_guard<std::mutex> one_change(worker_control_changes_);
        if (absl::Status s = worker_states_->Put(*key, control); !s.ok()) return s;
        scheduler_.SetWorkerControl(*key, control);
    }
    std::vector<WorkerStatus> named = scheduler_.Workers();
    std::erase_if(named,
                  [&](const WorkerStatus& w) { return (w.name.empty() ? w.id : w.name) != *key; });
    return named;
}

absl::StatusOr<JobRecord> Farm::SetPriority(const std::string& job_id, int priority) {
    return scheduler_.SetPriority(job_id, priority);
}

}  // namespace lf

namespace lf {

absl::StatusOr<JobRecord> Farm::Requeue(const std::string& job_id,
                                        const std::optional<FrameRange>& frames) {
    std::lock_guard<std::mutex> one_change(ended_job_changes_);
    // No longer recorded: removed, so that nothing serves the old EXR under the frame's name.
    const auto remove_files = [&](const std::vector<int>& dropped) {
        for (int frame : dropped) {
            std::error_code ignored;  // a frame whose EXR was never written
            fs::remove(FramePathOf("results", job_id, frame), ignored);
        }
    };
    absl::StatusOr<Scheduler::Requeued> requeued =
        frames ? scheduler_.RequeueFrames(job_id, *frames, remove_files)
               : scheduler_.RequeueJob(job_id);
    if (!requeued.ok()) return requeued.status();
    if (requeued->rendered) (void)FinishJob({job_id, requeued->run});
    return requeued->record;
}

}  // namespace lf
