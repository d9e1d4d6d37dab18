// The server's logic behind its gRPC services, in plain C++ types: taking a job in (checking its
// blobs and its scene), taking results in (decoding and merging them, writing the EXR when the
// last one arrives), and finding result files. Everything else is the scheduler's and the blob
// store's, which the services use directly.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/core/dir_lock.h"
#include "lf/job/plan.h"
#include "lf/job/render_metadata.h"
#include "lf/job/task_status.h"
#include "lf/server/blob_store.h"
#include "lf/server/job_notifier.h"
#include "lf/server/job_store.h"
#include "lf/server/scheduler.h"
#include "lf/server/sqlite_job_store.h"
#include "lf/server/task_log_store.h"
#include "lf/server/worker_state_store.h"

namespace lf {

// What one job may ask for; a submission beyond these is refused before anything is planned.
struct JobLimits {
    uint64_t max_scene_bytes = uint64_t(1) << 30;  // the scene JSON and its files together
    int max_resolution = 16384;                    // pixels per side
    uint64_t max_spp = uint64_t(1) << 20;
};

// Strings from the wire that the server keeps and lists: bounded so no request can make
// `lightfarm list` fail for everyone.
constexpr size_t kMaxJobNameBytes = 256;
constexpr size_t kMaxRequestIdBytes = 128;

// A blob no job names is kept this long after it was uploaded, or last found stored by
// MissingBlobs or BlobUploadOffset: its client may be about to submit the job that names it.
constexpr absl::Duration kUnusedBlobGrace = absl::Hours(1);
// A partial upload not written for this long is given up and removed.
constexpr absl::Duration kPartialUploadLifetime = absl::Hours(24);
// The most task log lines one TaskLogs call returns.
constexpr int kMaxTaskLogPage = 1000;

struct FarmOptions {
    std::string data_dir;  // jobs.db, logs.db, workers.db, blobs/, results/, previews/, scratch/
    SchedulerOptions scheduler;
    TaskLogLimits task_logs;
    JobLimits limits;
    // Ended jobs older than this are deleted (see DeleteExpired); zero keeps them forever.
    absl::Duration retention = absl::ZeroDuration();
    // lightfarm-server --notify-url: where each ended job is POSTed (lf/server/job_notifier.h);
    // "" for nowhere.
    std::string notify_url;
    JobNotifierOptions notify;
    // lightfarm-server --inline-radiosity-bytes: a radiosity sweep's input up to this size
    // goes with the leases; larger (or with 0, always) it is stored as a blob that workers
    // fetch, as the solution always is. At most kMaxInlineRadiosityBytes.
    size_t inline_radiosity_bytes = kMaxInlineRadiosityBytes;
};

class Farm {
  public:
    // Opens the data folder and takes up the jobs it holds that have not ended (see
    // Scheduler::Recover), writing the results of those that were fully rendered. Locks the
    // folder for the Farm's life (FailedPrecondition when another server holds it), removes the
    // temporary files a killed server left, and deletes the jobs past retention.
    static absl::StatusOr<std::unique_ptr<Farm>> Open(const FarmOptions& options);

    // Checks the limits, the paths and blobs and that the scene loads (InvalidArgument with the
    // loader's message when it does not), fills in the image size and scene hash, and queues the
    // job. ResourceExhausted, naming the limit, for a job above the limits.
    absl::StatusOr<std::string> Submit(JobSpec spec);

    // A blob upload from byte `offset` (BlobStore::StartUpload), refused when the blob alone is
    // above the scene size limit.
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> StartUpload(const std::string& hash,
                                                                   uint64_t size,
                                                                   uint64_t offset = 0);

    // Decodes and merges a task's result; writes the job's EXR when it was the last one.
    // `radiosity`: what the worker's radiosity solve reported, for that EXR's header. `splats`:
    // a splat task's splat list (lf::EncodeSplatList), with `tile_sums` its camera part. A
    // result that does not decode, or does not fit its task, is refused naming the job, the
    // task and the worker, and the task goes back to the queue as a counted failure.
    // A shot's task names its `frame`; a chunk of a shot sends one part a frame's task, in its
    // lease's order, instead of `tile_sums` and `splats`. Each frame the result completes is
    // written as its own EXR at once (fetchable whatever the job ends as). `times`: what the
    // task (and each part) cost on the worker, for the job's history.
    struct ResultPart {
        int frame = 0;
        std::string_view tile_sums;
        std::optional<std::string_view> splats;
        TaskTimes times;
    };
    absl::Status Complete(const std::string& lease_id, const std::string& worker,
                          std::string_view tile_sums,
                          std::optional<RadiosityFigures> radiosity = std::nullopt,
                          std::optional<std::string_view> splats = std::nullopt,
                          std::optional<int> frame = std::nullopt,
                          const std::vector<ResultPart>& parts = {}, const TaskTimes& times = {});
    // A radiosity patch-group task's result (lf::EncodeSweepResults: one a chunk of the task);
    // when it ends a sweep, stores the next sweep's input or the solution as a blob for the
    // workers. `links`: a sweep-0 task's chunk's link figures (hierarchical radiosity), which
    // the header sums.
    absl::Status CompleteSweep(const std::string& lease_id, const std::string& worker,
                               std::string_view sweep_result, const TaskTimes& times = {},
                               const std::optional<RadiosityFigures>& links = std::nullopt);

    // The EXR of a succeeded job; with `preview`, also of a running one (what is merged so far).
    // A preview is written again only when a task was merged since the last one. A shot's
    // `frame`: its EXR once the frame is complete, whatever the job's state (a cancelled or
    // failed shot keeps its finished frames); with `preview`, what is merged of it so far.
    absl::StatusOr<std::string> ResultFile(const std::string& job_id, bool preview,
                                           std::optional<int> frame = std::nullopt);

    // What the server's timer thread runs every tenth of a second: expired leases go back to the
    // queue, and adaptive jobs past their time limit stop sampling (and are written if that
    // completes them).
    void CheckTimers();

    // Removes an ended job: its record, task results, result and preview files, and the blobs
    // no other job uses (RemoveUnusedBlobs). FailedPrecondition for a job that has not ended.
    absl::Status DeleteJob(const std::string& job_id);
    // Deletes the jobs that ended more than options().retention before `now`, then removes
    // unused blobs and stale partial uploads (RemoveUnusedBlobs); returns how many jobs.
    absl::StatusOr<int> DeleteExpired(absl::Time now);
    // Removes the blobs that no job in the store or in memory names or reads (radiosity sweeps)
    // and that were not uploaded or found stored within kUnusedBlobGrace before `now`, and the
    // partial uploads not written within kPartialUploadLifetime.
    absl::StatusOr<BlobStore::Removed> RemoveUnusedBlobs(absl::Time now);

    // A job's tasks: a queued or running job's as the scheduler holds them now, an ended job's
    // as recorded when it ended. NotFound for a job the farm does not know.
    absl::StatusOr<std::vector<TaskStatus>> Tasks(const std::string& job_id);
    // The job's captured task log lines after `after_seq` (one task's when `task` is set), at
    // most `max_lines` of them (kMaxTaskLogPage when 0 or more). NotFound for a job the farm
    // does not know, or a `task` the job does not have.
    absl::StatusOr<TaskLogPage> TaskLogs(const std::string& job_id, std::optional<int> task,
                                         int64_t after_seq, int max_lines);
    // Keeps the log lines a worker sent with a heartbeat or a result of lease `lease_id`, under
    // its task and attempt. Call before the result is taken: the job may end with it. Lines of
    // a lease `worker` does not hold, or of an ended job, are dropped (and Ok returned).
    absl::Status TakeTaskLog(const std::string& lease_id, const std::string& worker,
                             std::vector<TaskLogLine> lines);
    // A queued or running job's new priority; FailedPrecondition once it has ended.
    absl::StatusOr<JobRecord> SetPriority(const std::string& job_id, int priority);

    // Worker control (issue 30): disables, enables or drains the workers of a name, or the one of
    // an id (Scheduler::WorkerKey), durably (workers.db) before it takes effect. Returns the
    // workers of that name known now; NotFound naming `name_or_id` for a worker never heard of.
    absl::StatusOr<std::vector<WorkerStatus>> SetWorkerState(const std::string& name_or_id,
                                                             WorkerControl control);
    // Job management (issue 30): Scheduler::RequeueJob, or with `frames` RequeueFrames (those
    // frames' EXRs removed), and a job it finds fully rendered written and finished.
    absl::StatusOr<JobRecord> Requeue(const std::string& job_id,
                                      const std::optional<FrameRange>& frames = std::nullopt);

    Scheduler& scheduler() { return scheduler_; }
    BlobStore& blobs() { return *blobs_; }
    const SqliteJobStore& store() const { return *store_; }
    const FarmOptions& options() const { return options_; }

  private:
    Farm(const FarmOptions& options, std::unique_ptr<BlobStore> blobs,
         std::unique_ptr<SqliteJobStore> store, std::unique_ptr<TaskLogStore> logs);
    absl::Status CheckSceneSize(uint64_t bytes) const;
    // A result that is not one: the task goes back to the queue as a counted failure.
    absl::Status RefuseUndecodable(const std::string& lease_id, const std::string& worker,
                                   const absl::Status& why);
    // Writes the merged image with the render's header attributes, atomically; the image's own
    // error estimates only when `complete` (a preview has pixels without samples).
    absl::Status WriteImage(const Scheduler::JobImage& snapshot, bool complete,
                            const std::string& path);
    // Writes the job's result and ends it. `last`: the completion that rendered it, whose record
    // is awaited after the image is written and before the job ends (a record that failed fails
    // the job instead, and its image is removed); its status is the worker's answer.
    // A run that has ended before its image is read (Scheduler::JobRun) is not ended again.
    absl::Status FinishJob(const Scheduler::JobRun& rendered,
                           const Scheduler::Completion* last = nullptr);
    // Writes a shot's complete frame `frame` as results/JOB.frame<N>.exr, its header the frame's
    // (MetadataOf(FrameSpec)), and records it; a failed write fails the job.
    // Nothing is written for a run that has ended, and a frame written as it ended is removed.
    void WriteFrame(const Scheduler::JobRun& run, int frame);
    std::string FramePathOf(const std::string& dir, const std::string& job_id, int frame) const;
    void RemoveJobFiles(const std::string& job_id);
    void RemoveJobLogs(const std::vector<std::string>& job_ids);
    // The temporary files of writes a killed server did not finish.
    void SweepTemporaryFiles();
    // Snapshot and WriteImage, one job at a time: the image being written is the only one in
    // the server's memory (the merged tiles are in files, lf/job/tile_store.h).
    // `run`: only that run's image (FailedPrecondition for another's, as for an ended job).
    absl::Status WriteSnapshot(const std::string& job_id, bool complete, const std::string& path,
                               std::optional<uint64_t> run = std::nullopt);

    const FarmOptions options_;
    std::unique_ptr<DirLock> lock_;
    // Radiosity figures of running jobs, for their EXR headers: the workers' reports, and of
    // jobs solved in sweeps, the iterations and residual of the farm's own solve. Kept in
    // memory: after a restart a header lacks what the workers reported before it.
    std::mutex radiosity_mutex_;
    struct SweepSolveFigures {
        int iterations = 0;
        double residual = 0;
    };
    // Hierarchical sweeps: each chunk's link figures, by run and chunk (soft state, as the
    // solve: a restart solves again and reports them again). By run: a job requeued while an
    // earlier run's image was written keeps its own.
    std::map<Scheduler::JobRun, std::map<int, RadiosityFigures>> sweep_links_;
    std::map<Scheduler::JobRun, RadiosityFigures> radiosity_;
    std::map<Scheduler::JobRun, SweepSolveFigures> sweep_solves_;
    std::unique_ptr<BlobStore> blobs_;
    // Shared by a submission from its blob checks until its job is held by the scheduler, and
    // taken alone by RemoveUnusedBlobs, so that no blob goes between the two.
    std::shared_mutex blob_users_;
    // Taken by Requeue, DeleteJob and each page of DeleteExpired: an ended job is requeued or
    // deleted, never both at once (a requeue's record written after the delete would bring the
    // job back without its results, logs or blobs; a delete after the requeue would drop a
    // running job's record).
    std::mutex ended_job_changes_;
    std::unique_ptr<SqliteJobStore> store_;
    std::unique_ptr<TaskLogStore> logs_;
    std::unique_ptr<WorkerStateStore> worker_states_;  // set by Open
    std::mutex worker_control_changes_;                // taken by SetWorkerState
    std::unique_ptr<JobNotifier> notifier_;            // set by Open, with a notify_url
    Scheduler scheduler_;
    std::mutex image_mutex_;
    std::map<std::string, int> previewed_;  // tasks done at each running job's last preview
};

}  // namespace lf
