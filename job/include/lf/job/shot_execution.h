// A shot on the farm: one job whose frames each run as the still of that frame would
// (MakeJobExecution(FrameSpec(spec, f))), composed behind one JobExecution so the scheduler,
// the job store and the workers see one job. Frames are independent: each keeps its own plan,
// merger and tile stores, and completes on its own.
//
// Tasks: with chunk 1 the shot's task indices are the frames' tasks, frame after frame (a task
// a frame appends later, an adaptive pass, takes the next free index). With chunk N > 1 task c
// is frames [cN, cN + N) of the range, every task of each, leased as the parts of one task and
// run by one worker: only kinds whose plan is fixed at the start chunk (fixed tiles, radiosity
// solved on each worker, the splatting methods); ShotExecution::Make refuses the others.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lf/job/job_execution.h"

namespace lf {

class ShotExecution : public JobExecution {
  public:
    // `spec` must be validated and have shot.frames. InvalidArgument naming the setting when a
    // frame cannot be planned, for radiosity solved in sweeps (its sweeps are one per job), and
    // for chunks of a kind that grows as it merges (adaptive sampling).
    static absl::StatusOr<std::unique_ptr<ShotExecution>> Make(const JobSpec& spec,
                                                               const TileStoreFactory& tile_stores);

    size_t task_count() const override;
    int tasks_total() const override;
    size_t tasks_done() const override;
    bool Complete() const override;
    const RenderStats& stats() const override;
    std::string Summary() const override;
    std::vector<int> Start() override;
    uint64_t QueueRank(int task) const override;
    void Lease(int task, const std::string& worker, TaskAssignment& lease) override;
    std::string PreferredWorker(int task) const override;
    void Describe(int task, TaskStatus& status) const override;
    uint64_t TaskSamples(int task) const override;
    size_t ResultParts(int task) const override;
    // The result must name the task's frame (TaskResult::frame), or for a chunk hold one part per
    // part of the lease, in its order. A chunk's parts merged before (a result refused half way)
    // are not merged again.
    absl::StatusOr<Merged> Merge(int task, const TaskResult& result) override;
    std::optional<std::string> RecordOf(const TaskResult& result) const override;
    absl::StatusOr<std::vector<int>> MergeRecorded(int task, std::string_view record) override;
    std::optional<std::vector<int>> EnforceTimeLimit(absl::Time started, absl::Time now) override;
    std::optional<absl::Duration> time_limit() const override;
    void AddBlobsInUse(std::set<std::string>& hashes) const override;
    // The first frame not complete, or the last frame once every one is.
    ImageReader SnapshotReader() const override;
    std::vector<FrameProgress> Frames() const override;
    const JobExecution* FrameExecution(int frame) const override;

    const FrameRange& frames() const { return frames_; }
    int chunk() const { return chunk_; }
    // By position in the range (0 for its first frame): the frame's own execution, complete
    // when every task of it is merged.
    const JobExecution& frame(int index) const { return *frames_exec_[size_t(index)]; }
    int frames_done() const;
    // Where a shot task lies: its frame's position and its index among that frame's tasks; for a
    // chunk, its first frame and task 0.
    std::pair<int, int> Locate(int task) const;
    // The frames (numbers, not positions) task `task` renders.
    std::vector<int> FramesOf(int task) const;

  private:
    ShotExecution(const JobSpec& spec, std::vector<std::unique_ptr<JobExecution>> frames);
    // Gives every task frame `index` planned that has no shot index yet the next one.
    void Index(int index);
    // Chunk `c`'s parts: (frame position, the frame's task), in lease order.
    std::vector<std::pair<int, int>> PartsOf(int c) const;
    std::pair<int, int> FramesOfChunk(int c) const;  // positions [begin, end)
    absl::StatusOr<std::vector<int>> MergePart(int index, int task, const TaskResult& part);

    FrameRange frames_;
    int chunk_ = 1;
    int width_ = 0, height_ = 0;
    uint64_t spp_ = 0;  // a chunk's samples per pixel, as Describe shows it
    std::vector<std::unique_ptr<JobExecution>> frames_exec_;
    // chunk 1: shot index -> (frame position, frame task), and back per frame.
    std::vector<std::pair<int, int>> located_;
    std::vector<std::vector<int>> shot_index_;
    // chunk > 1: which parts of each chunk are merged.
    std::vector<std::vector<bool>> parts_merged_;
    mutable RenderStats stats_;
};

// Whether a task of `spec` (a shot with shot.chunk > 1) may hold several frames: the kinds
// whose plan is fixed when the job starts, and a chunk whose result (one message and one record
// of every frame's sums) stays under kMaxTaskResultBytes. InvalidArgument naming the setting
// otherwise.
absl::Status CheckShotChunk(const JobSpec& spec);

}  // namespace lf
