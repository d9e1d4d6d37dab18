// A stateless farm worker: leases a task, renders its tile and sample range (or sweeps its
// patch groups of a radiosity solve), hands back the result, and again. The only state kept
// between tasks is a cache: scene blobs on disk, and the last job's built scene, radiosity
// form-factor rows and solution in memory.
#pragma once

#include <tbb/task_arena.h>

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "absl/status/status.h"
#include "lf/core/camera.h"
#include "lf/core/splat_list.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/radiance.h"
#include "lf/kernels/radiosity.h"
#include "lf/kernels/splat_renderer.h"
#include "lf/worker/blob_cache.h"
#include "lf/worker/server_connection.h"
#include "lf/worker/task_log_sink.h"

namespace lf {

struct WorkerOptions {
    int threads = 1;
    // An idle worker long-polls the server for this long per call...
    absl::Duration lease_wait = absl::Seconds(1);
    // ...and backs off from this to that while the server cannot be reached.
    absl::Duration min_idle = absl::Milliseconds(50), max_idle = absl::Seconds(1);
    // Tests only (lightfarm-worker --fail-tasks-for-test): every task fails at once, as on a
    // broken machine, for the farm tests of retries and the blocklist.
    bool fail_tasks_for_test = false;
};

class Worker {
  public:
    // `logs`: the sink that captures each task's lines (TaskLogSink::Install), sent with the
    // task's heartbeats and its result.
    Worker(WorkerOptions options, ServerConnection& server, BlobCache& cache, TaskLogSink& logs);
    // Sends the result handed over last, then returns.
    ~Worker();

    // Leases and renders tasks until Stop.
    void Run();
    // Thread-safe: stops the current task, hands it back, and makes Run return.
    void Stop();

  private:
    struct LoadedScene {
        std::string job_id;
        std::unique_ptr<Scene> scene;  // EmbreeScene keeps a reference
        std::unique_ptr<EmbreeScene> embree;
        std::unique_ptr<Camera> camera;
        std::unique_ptr<RadianceEstimator> tracer;  // path or Whitted tracer, radiosity display
        std::unique_ptr<SplatRenderer> frame;       // a splatting method's (light, bdpt, ppm)
        // Radiosity solved in sweeps: the mesh and system (or cluster tree), and the form-factor
        // rows (or links) of the chunks this worker swept (the server gives a chunk back to the
        // worker that has its rows), and the last input and its pull (hierarchical; the same for
        // all the chunks, so pulled once a sweep).
        std::unique_ptr<RadiositySweepChunks> sweeps;
        std::string input_hash;
        std::vector<Rgb> input;
        std::optional<std::string> pulled_hash;  // the input pulled; "": sweep 0's start
        std::vector<NodeExitance> pulled;
        // A shot's: the frame the scene is posed at (the BVH, camera and kernels are of it).
        std::optional<int> posed_frame;
    };

    void Execute(const TaskAssignment& task);
    // A sweep (after the first) of chunks whose links this worker made for the task's job.
    bool SweepsHeldLinks(const TaskAssignment& task) const;
    // The job's scene, built once for consecutive tasks of the same job.
    // Each returns Cancelled soon after `cancel` is set.
    absl::Status PrepareScene(const TaskAssignment& task, const std::atomic<bool>& cancel);
    // The job's path tracer or radiosity display, built once per job.
    absl::Status PrepareTracer(const TaskAssignment& task, const std::atomic<bool>& cancel);
    // Poses the job's scene at `frame` (lf::PoseSceneAtFrame) and rebuilds its BVH, camera and
    // kernels when the animation moves something; nothing when it is posed there already.
    absl::Status PoseFrame(const TaskAssignment& task, int frame, const std::atomic<bool>& cancel);
    // A chunk of a shot: each part in order, posed at its frame, one result a part.
    absl::Status RunChunk(const TaskAssignment& task, const std::atomic<bool>& cancel,
                          ServerConnection::TaskResult& result, RenderStats& stats);
    TileSums Render(const TaskAssignment& task, const std::atomic<bool>& cancel);
    // A tile or splat task's camera sums, or a sweep's result: `result` and its stats.
    // `frame_splats`: see RenderSplat.
    absl::Status RunTask(const TaskAssignment& task, const std::atomic<bool>& cancel,
                         ServerConnection::TaskResult& result, RenderStats& stats,
                         SplatList* frame_splats = nullptr);
    // A splatting method's task (lf::SplatTask): its camera sums and its splat list, encoded; the
    // renderer is built once per job. FailedPrecondition when the result is above what the
    // coordinator takes (lf::kMaxTaskResultBytes). With `frame_splats` (a chunk's list of the
    // task's frame) the splats are added to it instead, and `result.splats` stays unset.
    absl::Status RenderSplat(const TaskAssignment& task, const std::atomic<bool>& cancel,
                             ServerConnection::TaskResult& result, RenderStats& stats,
                             SplatList* frame_splats);
    // The sweep results of the task's chunks (linking those this worker does not hold yet),
    // and in sweep 0 in `figures` its chunk's link figures (RadiositySweepChunks::LinkReport).
    absl::StatusOr<std::string> Sweep(const TaskAssignment& task, const std::atomic<bool>& cancel,
                                      std::optional<RadiosityFigures>& figures);
    // The radiosity vector a task reads: the bytes that came with its lease, else the blob
    // `radiosity_hash` the server stored.
    absl::StatusOr<std::vector<Rgb>> ReadRadiosity(const TaskAssignment& task);
    // Hands the result to the sender thread, after the previous one was sent: the upload of a
    // result overlaps the lease and render of the next task (over a slow link, a 64x64 tile's
    // 400 kB take a few hundred milliseconds), and at most one result waits in memory.
    void SendResult(const TaskAssignment& task, ServerConnection::TaskResult result,
                    double seconds);
    void SenderLoop();
    // Waits until the result handed over last is sent.
    void FlushSends();
    bool stopping() const { return stopping_.load(); }
    void WaitIdle(absl::Duration d);

    const WorkerOptions options_;
    ServerConnection& server_;
    BlobCache& cache_;
    TaskLogSink& logs_;
    LoadedScene loaded_;
    tbb::task_arena arena_;

    std::atomic<bool> stopping_{false};
    std::mutex mutex_;
    std::condition_variable wake_;
    std::atomic<bool>* current_cancel_ = nullptr;  // guarded by mutex_

    struct PendingResult {
        TaskAssignment task;
        ServerConnection::TaskResult result;
        double seconds = 0;
    };
    std::mutex send_mutex_;
    std::condition_variable send_cv_;
    std::optional<PendingResult> pending_;  // guarded by send_mutex_: handed over, not yet sent
    bool sending_ = false;                  // guarded by send_mutex_
    bool sender_stop_ = false;              // guarded by send_mutex_
    std::thread sender_;                    // last: starts once the rest is built
};

}  // namespace lf
