// A shot as one job: its task indices over the frames' own plans, chunks of whole frames, each
// frame completing on its own, results refused for another frame, and a restart that merges the
// recorded results again frame by frame.
#include "lf/job/shot_execution.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

// Every sample of `task` at `value`.
TileSums Flat(const RenderTask& task, float value) {
    TileSums sums(task.rect);
    for (PixelSums& p : sums.pixels) {
        for (uint64_t s = task.sample_begin; s < task.sample_end; ++s) p.Add(s, Rgb(value));
    }
    sums.stats.samples =
        uint64_t(task.rect.width) * task.rect.height * (task.sample_end - task.sample_begin);
    return sums;
}

// Frames `frames` of a 16x16 image in 8x8 tiles at 4 spp: 4 tasks a frame.
JobSpec Shot(FrameRange frames, int chunk = 1) {
    JobSpec spec;
    spec.plan = {16, 16, 4, 8, 1};
    spec.shot.frames = frames;
    spec.shot.chunk = chunk;
    return spec;
}

std::unique_ptr<ShotExecution> Make(const JobSpec& spec) {
    auto made = ShotExecution::Make(spec, MakeMemoryTileStore);
    EXPECT_TRUE(made.ok()) << made.status();
    return made.ok() ? std::move(*made) : nullptr;
}

TaskAssignment LeaseOf(JobExecution& e, int task) {
    TaskAssignment lease;
    e.Lease(task, "w", lease);
    return lease;
}

// The result a worker sends for shot task `task`, frame f's pixels at f / 10.
struct Result {
    std::vector<TileSums> sums;
    TaskResult result;
};
Result Render(JobExecution& e, int task) {
    const TaskAssignment lease = LeaseOf(e, task);
    Result r;
    if (lease.parts.empty()) {
        r.sums.push_back(Flat(lease.task, float(*lease.frame) / 10));
        r.result = {.sums = &r.sums[0], .frame = lease.frame};
        return r;
    }
    r.sums.reserve(lease.parts.size());
    for (const TaskAssignment::Part& part : lease.parts) {
        r.sums.push_back(Flat(part.task, float(part.frame) / 10));
        r.result.parts.push_back({.sums = &r.sums.back(), .frame = part.frame});
    }
    return r;
}

TEST(ShotExecution, MakeJobExecutionMakesOneForAShotEvenOfOneFrame) {
    auto shot = MakeJobExecution(Shot({7, 7, 1}), MakeMemoryTileStore);
    ASSERT_TRUE(shot.ok()) << shot.status();
    EXPECT_NE(dynamic_cast<ShotExecution*>(shot->get()), nullptr);
    EXPECT_EQ(LeaseOf(**shot, 0).frame, 7);
    JobSpec still = Shot({1, 1, 1});
    still.shot.frames.reset();
    auto made = MakeJobExecution(still, MakeMemoryTileStore);
    ASSERT_TRUE(made.ok()) << made.status();
    EXPECT_EQ(dynamic_cast<ShotExecution*>(made->get()), nullptr);
    EXPECT_FALSE(LeaseOf(**made, 0).frame.has_value()) << "a still's lease names no frame";
}

TEST(ShotExecution, TaskIndicesRunFrameAfterFrame) {
    std::unique_ptr<ShotExecution> e = Make(Shot({10, 14, 2}));  // frames 10, 12, 14
    ASSERT_NE(e, nullptr);
    EXPECT_EQ(e->task_count(), 12u);
    EXPECT_EQ(e->tasks_total(), 12);
    std::vector<int> all(12);
    for (int t = 0; t < 12; ++t) all[size_t(t)] = t;
    EXPECT_EQ(e->Start(), all);
    EXPECT_EQ(e->Locate(5), std::make_pair(1, 1));
    const TaskAssignment lease = LeaseOf(*e, 5);
    EXPECT_EQ(lease.frame, 12);
    EXPECT_EQ(lease.task.index, 5) << "the shot's index, which the worker and its logs name";
    EXPECT_EQ(LeaseOf(*e, 9).task.index, 9);
    EXPECT_EQ(lease.task.rect.x0, 8) << "the frame's second tile";
    EXPECT_EQ(lease.task.rect.y0, 0);
    TaskStatus status;
    e->Describe(9, status);
    EXPECT_EQ(status.frames, std::vector<int>{14});
    EXPECT_EQ(status.width, 8);
    EXPECT_LT(e->QueueRank(3), e->QueueRank(4)) << "frames finish in order";
}

TEST(ShotExecution, EachFrameCompletesOnItsOwn) {
    std::unique_ptr<ShotExecution> e = Make(Shot({1, 3, 1}));
    ASSERT_NE(e, nullptr);
    e->Start();
    std::vector<int> completed;
    for (int t : {4, 5, 6, 0, 7}) {  // frame 2 whole, frame 1 begun
        Result r = Render(*e, t);
        absl::StatusOr<JobExecution::Merged> merged = e->Merge(t, r.result);
        ASSERT_TRUE(merged.ok()) << merged.status();
        completed.insert(completed.end(), merged->frames_completed.begin(),
                         merged->frames_completed.end());
    }
    EXPECT_EQ(completed, std::vector<int>{2}) << "reported by the result that completed it";
    EXPECT_EQ(e->frames_done(), 1);
    EXPECT_TRUE(e->frame(1).Complete());
    EXPECT_FALSE(e->frame(0).Complete());
    EXPECT_EQ(e->frame(0).tasks_done(), 1u);
    EXPECT_EQ(e->FrameExecution(2), &e->frame(1));
    EXPECT_EQ(e->FrameExecution(4), nullptr);
    const std::vector<FrameProgress> frames = e->Frames();
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(frames[0], (FrameProgress{.frame = 1, .tasks_done = 1, .tasks_total = 4}));
    EXPECT_EQ(frames[1],
              (FrameProgress{.frame = 2, .tasks_done = 4, .tasks_total = 4, .done = true}));
    EXPECT_EQ(e->tasks_done(), 5u);
    EXPECT_FALSE(e->Complete());
    EXPECT_EQ(e->stats().samples, 5u * 8 * 8 * 4);
    // The preview is the first frame not complete: frame 1, one tile merged.
    const absl::StatusOr<Image> preview = e->SnapshotReader()();
    ASSERT_TRUE(preview.ok()) << preview.status();
    EXPECT_FLOAT_EQ(preview->FindChannel("R")->at(0), 0.1f);
}

TEST(ShotExecution, RefusesAResultOfAnotherFrameOrWithoutOne) {
    std::unique_ptr<ShotExecution> e = Make(Shot({1, 2, 1}));
    ASSERT_NE(e, nullptr);
    e->Start();
    Result r = Render(*e, 0);  // frame 1, tile 0
    TaskResult other = r.result;
    other.frame = 2;
    absl::StatusOr<JobExecution::Merged> merged = e->Merge(0, other);
    ASSERT_FALSE(merged.ok());
    EXPECT_EQ(merged.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(merged.status().message().find("frame 2 for a task of frame 1"), std::string::npos)
        << merged.status();
    other.frame.reset();
    EXPECT_EQ(e->Merge(0, other).status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(e->Merge(4, r.result).status().code(), absl::StatusCode::kInvalidArgument)
        << "frame 1's tile for frame 2's task";
    EXPECT_EQ(e->tasks_done(), 0u);
    EXPECT_TRUE(e->Merge(0, r.result).ok());
}

TEST(ShotExecution, AChunkIsEveryTaskOfItsFrames) {
    std::unique_ptr<ShotExecution> e = Make(Shot({1, 5, 1}, 2));  // {1, 2}, {3, 4}, {5}
    ASSERT_NE(e, nullptr);
    EXPECT_EQ(e->Start(), (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(e->task_count(), 3u);
    EXPECT_EQ(e->tasks_total(), 3);
    EXPECT_EQ(e->FramesOf(1), (std::vector<int>{3, 4}));
    EXPECT_EQ(e->FramesOf(2), (std::vector<int>{5}));
    const TaskAssignment lease = LeaseOf(*e, 1);
    ASSERT_EQ(lease.parts.size(), 8u);
    EXPECT_EQ(lease.task.index, 1);
    EXPECT_EQ(lease.parts[0].frame, 3);
    EXPECT_EQ(lease.parts[7].frame, 4);
    EXPECT_EQ(lease.parts[7].task.rect.x0, 8);
    EXPECT_EQ(lease.parts[7].task.rect.y0, 8);
    EXPECT_EQ(e->TaskSamples(1), 2u * 16 * 16 * 4);
    TaskStatus status;
    e->Describe(1, status);
    EXPECT_EQ(status.frames, (std::vector<int>{3, 4}));
    EXPECT_EQ(status.width, 16) << "whole frames";

    Result r = Render(*e, 1);
    TaskResult short_result = r.result;
    short_result.parts.pop_back();
    EXPECT_EQ(e->Merge(1, short_result).status().code(), absl::StatusCode::kInvalidArgument);
    // A part of the wrong rectangle stops the merge there; the parts before stay merged and the
    // retry merges the rest.
    TaskResult damaged = r.result;
    damaged.parts[5].sums = &r.sums[0];
    EXPECT_EQ(e->Merge(1, damaged).status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_TRUE(e->frame(2).Complete());
    EXPECT_FALSE(e->frame(3).Complete());
    EXPECT_EQ(e->tasks_done(), 0u);
    // The retry's parts merged before are not merged again, but they are recorded with the
    // rest: one without its sums is refused, not recorded from a null pointer.
    EXPECT_EQ(e->ResultParts(1), 8u);
    EXPECT_EQ(e->ResultParts(2), 4u);
    TaskResult hollow = r.result;
    hollow.parts[0].sums = nullptr;
    absl::StatusOr<JobExecution::Merged> refused = e->Merge(1, hollow);
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(refused.status().message().find("part 0 (frame 3)"), std::string_view::npos)
        << refused.status();
    EXPECT_FALSE(e->frame(3).Complete()) << "nothing merged";
    absl::StatusOr<JobExecution::Merged> merged = e->Merge(1, r.result);
    ASSERT_TRUE(merged.ok()) << merged.status();
    EXPECT_EQ(merged->frames_completed, std::vector<int>{4});
    EXPECT_TRUE(e->RecordOf(r.result).has_value());
    EXPECT_EQ(e->tasks_done(), 1u);
    EXPECT_EQ(e->frames_done(), 2);
}

TEST(ShotExecution, ChunksRefuseKindsThatGrowAsTheyMerge) {
    JobSpec adaptive = Shot({1, 4, 1}, 2);
    adaptive.adaptive.target_error = 0.05;
    absl::StatusOr<std::unique_ptr<ShotExecution>> made =
        ShotExecution::Make(adaptive, MakeMemoryTileStore);
    ASSERT_FALSE(made.ok());
    EXPECT_NE(made.status().message().find("chunk 2"), std::string::npos) << made.status();
    EXPECT_NE(made.status().message().find("--chunk 1"), std::string::npos) << made.status();
    EXPECT_EQ(CheckShotChunk(adaptive).code(), absl::StatusCode::kInvalidArgument);
    adaptive.shot.chunk = 1;
    EXPECT_TRUE(ShotExecution::Make(adaptive, MakeMemoryTileStore).ok());

    JobSpec sweeps = Shot({1, 4, 1});
    sweeps.method = "radiosity";
    sweeps.radiosity.solver = "jacobi";
    made = ShotExecution::Make(sweeps, MakeMemoryTileStore);
    ASSERT_FALSE(made.ok());
    EXPECT_NE(made.status().message().find("--solver gauss-seidel"), std::string::npos)
        << made.status();
    sweeps.radiosity.solver = "gauss-seidel";  // each worker solves: fixed tiles, chunks too
    sweeps.shot.chunk = 2;
    EXPECT_TRUE(ShotExecution::Make(sweeps, MakeMemoryTileStore).ok());

    JobSpec big = Shot({1, 100, 1}, 50);  // 50 frames of 4K: 43 GB in one result
    big.plan.width = 3840;
    big.plan.height = 2160;
    const absl::Status too_big = CheckShotChunk(big);
    EXPECT_NE(too_big.message().find("use a smaller --chunk"), std::string::npos) << too_big;
    big.shot.chunk = 1;
    EXPECT_TRUE(CheckShotChunk(big).ok());
    // Each pass of a tile is a part with the tile's sums: 4 frames of 1080p in 1 pass fit
    // (862 MB), in 2 they do not (1.7 GB).
    JobSpec passes = Shot({1, 8, 1}, 4);
    passes.plan.width = 1920;
    passes.plan.height = 1080;
    EXPECT_TRUE(CheckShotChunk(passes).ok());
    passes.plan.passes = 2;
    EXPECT_NE(CheckShotChunk(passes).message().find("use a smaller --chunk"), std::string::npos);
}

// Every frame's plan is held while the shot runs: the frames' tasks together are bounded, and
// the bound is checked on the first frame's plan, before the others are made.
TEST(ShotExecution, AShotOfTooManyTasksIsRefusedNamingTheBound) {
    JobSpec spec = Shot({1, 10000, 1});  // 10000 frames of 1080p in 8x8 tiles: 324M tasks
    spec.plan.width = 1920;
    spec.plan.height = 1080;
    absl::StatusOr<std::unique_ptr<ShotExecution>> made =
        ShotExecution::Make(spec, MakeMemoryTileStore);
    ASSERT_FALSE(made.ok());
    EXPECT_NE(made.status().message().find("10000 frames of 32400 tasks each"), std::string::npos)
        << made.status();
    EXPECT_NE(made.status().message().find("lf::kMaxShotTasks"), std::string::npos);
    spec.plan.tile = 64;  // 510 tasks a frame: 5.1M, still too many
    EXPECT_FALSE(ShotExecution::Make(spec, MakeMemoryTileStore).ok());
    spec.shot.frames = FrameRange{1, 2, 1};  // 1020 tasks
    EXPECT_TRUE(ShotExecution::Make(spec, MakeMemoryTileStore).ok());
}

TEST(ShotExecution, AChunkOfASplattingMethodLeasesEveryPassOfItsFrames) {
    JobSpec light = Shot({1, 3, 1}, 3);
    light.method = "light";
    std::unique_ptr<ShotExecution> e = Make(light);
    ASSERT_NE(e, nullptr);
    const size_t passes = e->frame(0).task_count();
    const TaskAssignment lease = LeaseOf(*e, 0);
    ASSERT_EQ(lease.parts.size(), 3 * passes);
    EXPECT_EQ(lease.parts.back().frame, 3);
    EXPECT_GT(lease.parts.back().path_end, lease.parts.back().path_begin);
    EXPECT_EQ(lease.parts[passes].path_begin, lease.parts[0].path_begin) << "each frame's plan";
    EXPECT_EQ(lease.parts[passes].frame, 2);
}

TEST(ShotExecution, ARangeNoSubmissionWouldTakeIsRefused) {
    // As a damaged job store could hand one back: never checked by CheckJobSettings.
    for (const FrameRange& bad : {FrameRange{5, 1, 1}, FrameRange{1, 5, 0}}) {
        absl::StatusOr<std::unique_ptr<ShotExecution>> made =
            ShotExecution::Make(Shot(bad), MakeMemoryTileStore);
        EXPECT_EQ(made.status().code(), absl::StatusCode::kInvalidArgument) << FrameRangeText(bad);
    }
}

TEST(ShotExecution, AdaptiveFramesAppendPassesUnderNewShotIndices) {
    JobSpec spec = Shot({1, 2, 1});
    spec.adaptive = {.target_error = 0.01, .max_spp = 16};
    std::unique_ptr<ShotExecution> e = Make(spec);
    ASSERT_NE(e, nullptr);
    std::vector<int> queue = e->Start();
    ASSERT_EQ(queue.size(), 8u);
    // Noisy A/B halves everywhere: every tile asks for another pass until max_spp.
    while (!queue.empty()) {
        const int t = queue.front();
        queue.erase(queue.begin());
        const TaskAssignment lease = LeaseOf(*e, t);
        TileSums sums(lease.task.rect);
        for (PixelSums& p : sums.pixels) {
            for (uint64_t s = lease.task.sample_begin; s < lease.task.sample_end; ++s) {
                p.Add(s, Rgb(s % 2 ? 0.2f : 0.8f));
            }
        }
        absl::StatusOr<JobExecution::Merged> merged =
            e->Merge(t, {.sums = &sums, .frame = lease.frame});
        ASSERT_TRUE(merged.ok()) << merged.status();
        for (int next : merged->appended) {
            EXPECT_GE(next, 8);
            EXPECT_EQ(LeaseOf(*e, next).frame, lease.frame) << "a pass of the same frame";
            queue.push_back(next);
        }
    }
    EXPECT_TRUE(e->Complete());
    EXPECT_GT(e->task_count(), 8u);
    EXPECT_EQ(e->frames_done(), 2);
}

// The coordinator restarted: the recorded results merged again give every frame's bits, in a
// plain shot and in chunks.
void ExpectRestartGivesTheSameFrames(const JobSpec& spec, const std::vector<int>& done) {
    std::unique_ptr<ShotExecution> live = Make(spec);
    std::unique_ptr<ShotExecution> restarted = Make(spec);
    ASSERT_TRUE(live && restarted);
    live->Start();
    std::map<int, std::string> records;
    for (int t : done) {
        Result r = Render(*live, t);
        ASSERT_TRUE(live->Merge(t, r.result).ok());
        const std::optional<std::string> record = live->RecordOf(r.result);
        ASSERT_TRUE(record.has_value());
        records[t] = *record;
    }
    for (const auto& [t, record] : records) {  // the store replays in index order
        ASSERT_TRUE(restarted->MergeRecorded(t, record).ok()) << t;
    }
    restarted->Start();
    EXPECT_EQ(restarted->tasks_done(), live->tasks_done());
    EXPECT_EQ(restarted->frames_done(), live->frames_done());
    for (int i = 0; i < spec.shot.frames->count(); ++i) {
        EXPECT_EQ(restarted->frame(i).Complete(), live->frame(i).Complete()) << i;
        const absl::StatusOr<Image> a = live->frame(i).SnapshotReader()();
        const absl::StatusOr<Image> b = restarted->frame(i).SnapshotReader()();
        ASSERT_TRUE(a.ok() && b.ok());
        for (const char* c : {"R", "A.G", "spp"}) {
            EXPECT_EQ(*a->FindChannel(c), *b->FindChannel(c)) << "frame position " << i << " " << c;
        }
    }
    // A record is merged only for its own task.
    const auto& [t, record] = *records.begin();
    EXPECT_FALSE(restarted->MergeRecorded(int(restarted->task_count()) - 1, record).ok());
}

TEST(ShotExecution, ARestartMergesTheRecordedResultsFrameByFrame) {
    ExpectRestartGivesTheSameFrames(Shot({1, 3, 1}), {7, 0, 4, 5, 6});
}

TEST(ShotExecution, ARestartMergesTheRecordedChunks) {
    ExpectRestartGivesTheSameFrames(Shot({1, 5, 1}, 2), {2, 0});
}

TEST(ShotExecution, ADamagedRecordIsRefused) {
    std::unique_ptr<ShotExecution> e = Make(Shot({1, 2, 1}));
    ASSERT_NE(e, nullptr);
    Result r = Render(*e, 0);
    const std::string record = *e->RecordOf(r.result);
    for (size_t cut : {size_t(0), size_t(5), size_t(9), size_t(14), record.size() - 1}) {
        EXPECT_FALSE(e->MergeRecorded(0, record.substr(0, cut)).ok()) << cut;
    }
    std::string huge = record;
    huge[7] = '\xff';  // the part count
    EXPECT_FALSE(e->MergeRecorded(0, huge).ok());
    EXPECT_FALSE(e->MergeRecorded(0, record + "x").ok());
    EXPECT_EQ(e->tasks_done(), 0u);
    EXPECT_TRUE(e->MergeRecorded(0, record).ok());
}

}  // namespace
}  // namespace lf
