// Each kind of job execution alone, with made-up results: which tasks start it, what a result
// appends or unlocks, which results it refuses, what it records for a restart, and its time
// limit. MakeJobExecution picks the kind from the spec.
#include "lf/job/job_execution.h"

#include <gtest/gtest.h>

#include <typeindex>

#include "lf/core/tile_codec.h"
#include "lf/job/adaptive_tile_execution.h"
#include "lf/job/splat_execution.h"
#include "lf/job/sweep_execution.h"
#include "lf/job/tile_execution.h"

namespace lf {
namespace {

// A result of every sample of `task` at `value`, the odd samples at `odd` (A/B halves).
TileSums Flat(const RenderTask& task, float value, float odd) {
    TileSums sums(task.rect);
    for (PixelSums& p : sums.pixels) {
        for (uint64_t s = task.sample_begin; s < task.sample_end; ++s) {
            p.Add(s, Rgb(s % 2 ? odd : value));
        }
    }
    sums.stats.samples =
        uint64_t(task.rect.width) * task.rect.height * (task.sample_end - task.sample_begin);
    return sums;
}

RenderTask TaskOf(JobExecution& execution, int t) {
    TaskAssignment lease;
    execution.Lease(t, "w", lease);
    return lease.task;
}

TEST(TileExecution, StartsWithEveryTileAndRefusesOtherKindsOfResult) {
    auto made = TileExecution::Make({16, 16, 4, 8, 1}, MakeMemoryTileStore);
    ASSERT_TRUE(made.ok()) << made.status();
    TileExecution& e = **made;
    EXPECT_EQ(e.Start(), (std::vector<int>{0, 1, 2, 3}));
    EXPECT_EQ(e.tasks_total(), 4);
    const TileSums sums = Flat(TaskOf(e, 0), 0.5f, 0.5f);
    SplatList splats(16, 16);
    const SweepChunkResult sweep;
    EXPECT_EQ(e.Merge(0, {.sums = &sums, .splats = &splats}).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(e.Merge(0, {.sweeps = {&sweep, 1}}).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(e.Merge(1, {.sums = &sums}).status().code(), absl::StatusCode::kInvalidArgument)
        << "another task's rectangle";
    absl::StatusOr<JobExecution::Merged> merged = e.Merge(0, {.sums = &sums});
    ASSERT_TRUE(merged.ok()) << merged.status();
    EXPECT_TRUE(merged->appended.empty());
    EXPECT_EQ(e.tasks_done(), 1u);
    EXPECT_FALSE(e.Complete());
    TaskStatus status;
    e.Describe(0, status);
    EXPECT_EQ(status.kind, TaskKind::kTile);
    EXPECT_EQ(e.TaskSamples(0), 8u * 8u * 4u);
}

TEST(TileExecution, RecordedResultsMergeToTheSameImage) {
    auto live = TileExecution::Make({16, 8, 4, 8, 1}, MakeMemoryTileStore);
    auto restarted = TileExecution::Make({16, 8, 4, 8, 1}, MakeMemoryTileStore);
    ASSERT_TRUE(live.ok() && restarted.ok());
    for (int t = 0; t < 2; ++t) {
        const TileSums sums = Flat(TaskOf(**live, t), 0.25f * float(t + 1), 0.5f);
        ASSERT_TRUE((*live)->Merge(t, {.sums = &sums}).ok());
        const std::optional<std::string> record = (*live)->RecordOf({.sums = &sums});
        ASSERT_TRUE(record.has_value());
        ASSERT_TRUE((*restarted)->MergeRecorded(t, *record).ok());
    }
    EXPECT_TRUE((*live)->Complete());
    EXPECT_TRUE((*restarted)->Complete());
    const absl::StatusOr<Image> a = (*live)->SnapshotReader()();
    const absl::StatusOr<Image> b = (*restarted)->SnapshotReader()();
    ASSERT_TRUE(a.ok() && b.ok());
    for (const char* c : {"R", "A.G", "B.B", "spp"}) {
        EXPECT_EQ(*a->FindChannel(c), *b->FindChannel(c)) << c;
    }
}

// The farm records a tile as the bytes it came in (TaskResult::encoded_sums), not encoded
// again; a restart merges those to the same image as the sums it decoded from them.
TEST(TileExecution, ARecordIsTheBytesTheSumsCameIn) {
    auto live = TileExecution::Make({16, 8, 4, 8, 1}, MakeMemoryTileStore);
    auto restarted = TileExecution::Make({16, 8, 4, 8, 1}, MakeMemoryTileStore);
    ASSERT_TRUE(live.ok() && restarted.ok());
    const std::string wire = EncodeTileSums(Flat(TaskOf(**live, 0), 0.25f, 0.75f));
    const absl::StatusOr<TileSums> sums = DecodeTileSums(wire);
    ASSERT_TRUE(sums.ok()) << sums.status();
    ASSERT_TRUE((*live)->Merge(0, {.sums = &*sums, .encoded_sums = wire}).ok());
    // Not the encoding of `sums` made again: given other bytes, the record is those.
    TileSums other = *sums;
    other.stats.samples += 1;
    const std::string given = EncodeTileSums(other);
    ASSERT_NE(given, wire);
    const std::optional<std::string> record =
        (*live)->RecordOf({.sums = &*sums, .encoded_sums = given});
    EXPECT_EQ(record, given) << "the record is the bytes given";
    const std::optional<std::string> own =
        (*live)->RecordOf({.sums = &*sums, .encoded_sums = wire});
    ASSERT_EQ(own, wire);
    ASSERT_TRUE((*restarted)->MergeRecorded(0, *own).ok());
    const absl::StatusOr<Image> a = (*live)->SnapshotReader()();
    const absl::StatusOr<Image> b = (*restarted)->SnapshotReader()();
    ASSERT_TRUE(a.ok() && b.ok());
    for (const char* c : {"R", "A.G", "B.B", "spp"}) {
        EXPECT_EQ(*a->FindChannel(c), *b->FindChannel(c)) << c;
    }
}

// 16x16 in 8x8 tiles, first pass 4 spp; tile (8, 8) is noisy (A 0.4, B 0.6), the others flat.
std::unique_ptr<AdaptiveTileExecution> Adaptive(const AdaptiveSettings& settings) {
    auto made =
        AdaptiveTileExecution::Make(16, 16, 4, 8, settings, kMaxTaskSamples, MakeMemoryTileStore);
    EXPECT_TRUE(made.ok()) << made.status();
    return std::move(*made);
}

TileSums Halves(const RenderTask& task) {
    const bool noisy = task.rect.x0 == 8 && task.rect.y0 == 8;
    return Flat(task, noisy ? 0.4f : 0.5f, noisy ? 0.6f : 0.5f);
}

TEST(AdaptiveTileExecution, AppendsPassesForTheNoisyTileOnly) {
    std::unique_ptr<AdaptiveTileExecution> e = Adaptive({.target_error = 0.1, .max_spp = 64});
    std::vector<int> queue = e->Start();
    EXPECT_EQ(queue, (std::vector<int>{0, 1, 2, 3}));
    std::vector<uint64_t> ranks;
    while (!queue.empty()) {
        const int t = queue.front();
        queue.erase(queue.begin());
        ranks.push_back(e->QueueRank(t));
        const TileSums sums = Halves(TaskOf(*e, t));
        absl::StatusOr<JobExecution::Merged> merged = e->Merge(t, {.sums = &sums});
        ASSERT_TRUE(merged.ok()) << merged.status();
        for (int next : merged->appended) {
            EXPECT_EQ(TaskOf(*e, next).rect.x0, 8);
            queue.push_back(next);
        }
    }
    EXPECT_EQ(ranks,
              (std::vector<uint64_t>{0, 0, 0, 0, 4, 18}));  // a pass ranks by its first sample
    EXPECT_TRUE(e->Complete());
    EXPECT_EQ(e->tasks_total(), 6);
    EXPECT_EQ(e->TileReport()->max_spp, 64u);
    EXPECT_FALSE(e->EnforceTimeLimit(absl::InfinitePast(), absl::Now()).has_value());
}

TEST(AdaptiveTileExecution, TimeLimitDropsPassesOnce) {
    std::unique_ptr<AdaptiveTileExecution> e = Adaptive({.time_limit = 5, .max_spp = 1 << 10});
    EXPECT_EQ(e->time_limit(), absl::Seconds(5));
    std::vector<int> second;
    for (int t : e->Start()) {
        const TileSums sums = Halves(TaskOf(*e, t));
        absl::StatusOr<JobExecution::Merged> merged = e->Merge(t, {.sums = &sums});
        ASSERT_TRUE(merged.ok());
        second.insert(second.end(), merged->appended.begin(), merged->appended.end());
    }
    EXPECT_EQ(second.size(), 4u);
    const absl::Time t0 = absl::FromUnixSeconds(1000);
    EXPECT_FALSE(e->EnforceTimeLimit(t0, t0 + absl::Seconds(4)).has_value());
    const std::optional<std::vector<int>> dropped = e->EnforceTimeLimit(t0, t0 + absl::Seconds(5));
    ASSERT_TRUE(dropped.has_value());
    EXPECT_EQ(*dropped, second);
    EXPECT_FALSE(e->EnforceTimeLimit(t0, t0 + absl::Seconds(6)).has_value()) << "once";
    EXPECT_EQ(e->tasks_total(), 4);
    EXPECT_TRUE(e->Complete());
    EXPECT_TRUE(e->TileReport()->timed_out);
}

TEST(SplatExecution, MergesCameraPartsAndSplatsAndRecordsBoth) {
    SplatPlanSettings plan;
    plan.width = 8;
    plan.height = 4;
    plan.kind = SplatPlanKind::kLightPaths;
    plan.light_paths = 64;
    plan.max_paths_per_task = 16;
    auto made = SplatExecution::Make(plan, MakeMemoryTileStore);
    ASSERT_TRUE(made.ok()) << made.status();
    SplatExecution& e = **made;
    ASSERT_EQ(e.Start().size(), 4u);
    TaskAssignment lease;
    e.Lease(1, "w", lease);
    EXPECT_EQ(lease.path_begin, 16u);
    EXPECT_EQ(lease.path_end, 32u);
    TaskStatus status;
    e.Describe(1, status);
    EXPECT_EQ(status.kind, TaskKind::kSplat);
    EXPECT_EQ(status.width, 8);  // a light-path task covers the frame
    const TileSums camera{PixelRect{}};
    EXPECT_EQ(e.Merge(0, {.sums = &camera}).status().code(), absl::StatusCode::kInvalidArgument);
    for (int t = 0; t < 4; ++t) {
        SplatList splats(8, 4);
        ASSERT_TRUE(e.Merge(t, {.sums = &camera, .splats = &splats}).ok());
        EXPECT_TRUE(e.RecordOf({.sums = &camera, .splats = &splats}).has_value());
    }
    EXPECT_TRUE(e.Complete());
    EXPECT_TRUE(e.SnapshotReader()().ok());
}

// A system of one unknown and no power: the first sweep solves it.
SweepChunkResult DarkChunk(int sweep) {
    SweepChunkResult r;
    r.sweep = sweep;
    r.sides = 1;
    r.change = {0};
    r.power = {0};
    r.input = {Rgb(0)};
    r.output = {Rgb(0)};
    return r;
}

// 16x8 pixels in two 8x8 tiles of 4096 samples a pixel: enough work a task to be kept as asked.
std::unique_ptr<SweepExecution> TwoTileSweeps(int sweep_tasks) {
    RadiositySettings radiosity;
    radiosity.sweep_tasks = sweep_tasks;
    absl::StatusOr<std::unique_ptr<SweepExecution>> made =
        SweepExecution::Make({16, 8, 4096, 8, 1}, radiosity, MakeMemoryTileStore);
    EXPECT_TRUE(made.ok()) << made.status();
    return made.ok() ? std::move(*made) : nullptr;
}

TEST(SweepExecution, SolvesBeforeTheTilesAndHandsTheSolutionOn) {
    const std::unique_ptr<SweepExecution> made = TwoTileSweeps(1);
    ASSERT_TRUE(made);
    SweepExecution& e = *made;
    EXPECT_EQ(e.Start(), std::vector<int>{2});  // sweep 0's chunk, after the two tiles
    EXPECT_EQ(e.task_count(), 3u);
    EXPECT_EQ(e.tasks_total(), 2);
    TaskAssignment lease;
    e.Lease(2, "w", lease);
    EXPECT_EQ(lease.sweep, 0);
    EXPECT_EQ(e.PreferredWorker(2), "w");
    EXPECT_EQ(e.TaskSamples(2), 0u);
    const TileSums sums = Flat(TaskOf(e, 0), 0.5f, 0.5f);
    EXPECT_EQ(e.Merge(2, {.sums = &sums}).status().code(), absl::StatusCode::kInvalidArgument);
    const SweepChunkResult wrong = DarkChunk(1);
    EXPECT_EQ(e.Merge(2, {.sweeps = {&wrong, 1}}).status().code(),
              absl::StatusCode::kInvalidArgument);
    const SweepChunkResult chunk = DarkChunk(0);
    EXPECT_EQ(e.Merge(0, {.sweeps = {&chunk, 1}}).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_FALSE(e.RecordOf({.sweeps = {&chunk, 1}}).has_value()) << "soft state";
    absl::StatusOr<JobExecution::Merged> merged = e.Merge(2, {.sweeps = {&chunk, 1}});
    ASSERT_TRUE(merged.ok()) << merged.status();
    ASSERT_TRUE(merged->sweep.has_value());
    EXPECT_TRUE(merged->sweep->converged);
    absl::StatusOr<std::vector<int>> tiles = e.Publish(true, "solution-hash");
    ASSERT_TRUE(tiles.ok());
    EXPECT_EQ(*tiles, (std::vector<int>{0, 1}));
    e.Lease(0, "w", lease);
    EXPECT_EQ(lease.radiosity_hash, "solution-hash");
    std::set<std::string> blobs;
    e.AddBlobsInUse(blobs);
    EXPECT_EQ(blobs, std::set<std::string>{"solution-hash"});
}

// A chunk belongs to the worker of its task's first lease: a straggler's second lease of the
// same task leaves it there (else that worker would take every later sweep of the chunk); the
// next sweep's task of a chunk whose owner is gone goes to whoever leases it.
TEST(SweepExecution, ASecondLeaseOfATaskLeavesTheChunkWithItsOwner) {
    const std::unique_ptr<SweepExecution> made = TwoTileSweeps(2);
    ASSERT_TRUE(made);
    SweepExecution& e = *made;
    const std::vector<int> sweep0 = e.Start();
    ASSERT_EQ(sweep0.size(), 2u);
    TaskAssignment lease;
    e.Lease(sweep0[0], "a", lease);
    e.Lease(sweep0[1], "b", lease);
    e.Lease(sweep0[1], "a", lease);  // the straggler's copy
    EXPECT_EQ(e.PreferredWorker(sweep0[0]), "a");
    EXPECT_EQ(e.PreferredWorker(sweep0[1]), "b");
    // Two unknowns, one a chunk, lit: sweep 0 does not converge.
    for (int chunk : {0, 1}) {
        SweepChunkResult r = DarkChunk(0);
        r.chunk = chunk;
        r.sides = 2;
        r.side_begin = chunk;
        r.output = {Rgb(1)};
        r.change = {1};
        absl::StatusOr<JobExecution::Merged> merged =
            e.Merge(sweep0[size_t(chunk)], {.sweeps = {&r, 1}});
        ASSERT_TRUE(merged.ok()) << merged.status();
    }
    absl::StatusOr<std::vector<int>> sweep1 = e.Publish(false, "b1-hash");
    ASSERT_TRUE(sweep1.ok()) << sweep1.status();
    ASSERT_EQ(sweep1->size(), 2u);
    EXPECT_EQ(e.PreferredWorker((*sweep1)[0]), "a");
    EXPECT_EQ(e.PreferredWorker((*sweep1)[1]), "b");
    e.Lease((*sweep1)[0], "b", lease);  // "a" is gone: the scheduler let "b" take it
    EXPECT_EQ(e.PreferredWorker((*sweep1)[0]), "b");
    EXPECT_EQ(lease.chunks, std::vector<int>{0});
}

// The results of `chunks` in `sweep` of a system of `of` unknowns, one a chunk, lit: each
// gathers 1 from sweep 0 on (so a later sweep's input is 1), never converging.
std::vector<SweepChunkResult> LitChunks(int sweep, const std::vector<int>& chunks, int of) {
    std::vector<SweepChunkResult> results;
    for (int chunk : chunks) {
        SweepChunkResult r = DarkChunk(sweep);
        r.chunk = chunk;
        r.sides = of;
        r.side_begin = chunk;
        r.input = {Rgb(sweep == 0 ? 0 : 1)};
        r.output = {Rgb(1)};
        r.change = {1};
        r.power = {1};
        results.push_back(r);
    }
    return results;
}

// A sweep's input published with its bytes is soft state: the bytes go with each lease of the
// sweep, and the blob is not kept from collection (it was never stored). The solution, which
// every display tile's lease would carry, is a stored blob.
TEST(SweepExecution, ASweepInputPublishedWithItsBytesGoesWithTheLeases) {
    const std::unique_ptr<SweepExecution> made = TwoTileSweeps(1);
    ASSERT_TRUE(made);
    SweepExecution& e = *made;
    const std::vector<int> sweep0 = e.Start();
    ASSERT_EQ(sweep0.size(), 1u);
    TaskAssignment lease;
    e.Lease(sweep0[0], "w", lease);
    EXPECT_EQ(lease.radiosity_input, nullptr) << "sweep 0 reads no input";
    const std::vector<SweepChunkResult> lit = LitChunks(0, {0}, 1);
    ASSERT_TRUE(e.Merge(sweep0[0], {.sweeps = lit}).ok());
    const auto bytes = std::make_shared<const std::string>("b1 bytes");
    absl::StatusOr<std::vector<int>> sweep1 = e.Publish(false, "b1-hash", bytes);
    ASSERT_TRUE(sweep1.ok()) << sweep1.status();
    ASSERT_EQ(sweep1->size(), 1u);
    e.Lease(sweep1->front(), "w", lease);
    EXPECT_EQ(lease.radiosity_hash, "b1-hash");
    ASSERT_NE(lease.radiosity_input, nullptr);
    EXPECT_EQ(*lease.radiosity_input, "b1 bytes");
    std::set<std::string> blobs;
    e.AddBlobsInUse(blobs);
    EXPECT_TRUE(blobs.empty()) << "b1-hash is not in the store";
    // Sweep 2's input is a stored blob (too large to travel, say): no bytes go with its leases.
    ASSERT_TRUE(e.Merge(sweep1->front(), {.sweeps = LitChunks(1, {0}, 1)}).ok());
    absl::StatusOr<std::vector<int>> sweep2 = e.Publish(false, "b2-hash");
    ASSERT_TRUE(sweep2.ok()) << sweep2.status();
    e.Lease(sweep2->front(), "w", lease);
    EXPECT_EQ(lease.radiosity_hash, "b2-hash");
    EXPECT_EQ(lease.radiosity_input, nullptr);
    e.AddBlobsInUse(blobs);
    EXPECT_EQ(blobs, std::set<std::string>{"b2-hash"});
    // The solution goes to every display tile's lease: it must be a stored blob.
    ASSERT_TRUE(e.Merge(sweep2->front(), {.sweeps = LitChunks(2, {0}, 1)}).ok());
    EXPECT_EQ(e.Publish(true, "solution-hash", bytes).status().code(),
              absl::StatusCode::kInvalidArgument);
    absl::StatusOr<std::vector<int>> tiles = e.Publish(true, "solution-hash");
    ASSERT_TRUE(tiles.ok()) << tiles.status();
    EXPECT_EQ(*tiles, (std::vector<int>{0, 1}));
    e.Lease(tiles->front(), "w", lease);
    EXPECT_EQ(lease.radiosity_hash, "solution-hash");
    EXPECT_EQ(lease.radiosity_input, nullptr);
    blobs.clear();
    e.AddBlobsInUse(blobs);
    EXPECT_EQ(blobs, std::set<std::string>{"solution-hash"});
}

// After sweep 0 (a task a chunk), each sweep has one task a worker, of every chunk it holds in
// chunk order: one lease and result a worker and sweep. A result must be of exactly its task's
// chunks, and is added whole or not at all. A worker gone gives its whole task to the next.
TEST(SweepExecution, LaterSweepsHaveOneTaskAWorkerOfAllItsChunks) {
    const std::unique_ptr<SweepExecution> made = TwoTileSweeps(5);
    ASSERT_TRUE(made);
    SweepExecution& e = *made;
    const std::vector<int> sweep0 = e.Start();
    ASSERT_EQ(sweep0, (std::vector<int>{2, 3, 4, 5, 6}));
    TaskAssignment lease;
    const std::vector<std::string> owner = {"a", "b", "a", "a", "b"};
    for (int c = 0; c < 5; ++c) {
        e.Lease(sweep0[size_t(c)], owner[size_t(c)], lease);
        EXPECT_EQ(lease.chunks, std::vector<int>{c});
        EXPECT_EQ(lease.sweep, 0);
        const std::vector<SweepChunkResult> r = LitChunks(0, {c}, 5);
        ASSERT_TRUE(e.Merge(sweep0[size_t(c)], {.sweeps = r}).ok());
    }
    absl::StatusOr<std::vector<int>> sweep1 = e.Publish(false, "h1");
    ASSERT_TRUE(sweep1.ok()) << sweep1.status();
    ASSERT_EQ(*sweep1, (std::vector<int>{7, 8}));  // numbered after sweep 0's
    EXPECT_EQ(e.task_count(), 9u);
    EXPECT_EQ(e.PreferredWorker(7), "a");
    EXPECT_EQ(e.PreferredWorker(8), "b");
    e.Lease(7, "a", lease);
    EXPECT_EQ(lease.sweep, 1);
    EXPECT_EQ(lease.chunks, (std::vector<int>{0, 2, 3}));
    EXPECT_EQ(lease.radiosity_hash, "h1");
    TaskStatus status;
    e.Describe(8, status);
    EXPECT_EQ(status.kind, TaskKind::kRadiositySweep);
    EXPECT_EQ(e.TaskSamples(8), 0u);
    // Another task's chunks, a chunk short, out of order, or of another sweep: refused, and
    // nothing of them is added (the right result is taken afterwards).
    for (const std::vector<SweepChunkResult>& wrong :
         {LitChunks(1, {1, 4}, 5), LitChunks(1, {0, 2}, 5), LitChunks(1, {2, 0, 3}, 5),
          LitChunks(0, {0, 2, 3}, 5)}) {
        EXPECT_EQ(e.Merge(7, {.sweeps = wrong}).status().code(),
                  absl::StatusCode::kInvalidArgument);
    }
    std::vector<SweepChunkResult> bad_input = LitChunks(1, {0, 2, 3}, 5);
    bad_input[2].sides = 6;  // its last chunk does not fit: the first two are not added either
    EXPECT_FALSE(e.Merge(7, {.sweeps = bad_input}).ok());
    absl::StatusOr<JobExecution::Merged> merged =
        e.Merge(7, {.sweeps = LitChunks(1, {0, 2, 3}, 5)});
    ASSERT_TRUE(merged.ok()) << merged.status();
    EXPECT_FALSE(merged->sweep.has_value()) << "b's chunks are still out";
    merged = e.Merge(8, {.sweeps = LitChunks(1, {1, 4}, 5)});
    ASSERT_TRUE(merged.ok()) << merged.status();
    ASSERT_TRUE(merged->sweep.has_value());
    // "b" is gone in sweep 2: "a" takes b's task, and with it chunks 1 and 4.
    absl::StatusOr<std::vector<int>> sweep2 = e.Publish(false, "h2");
    ASSERT_TRUE(sweep2.ok()) << sweep2.status();
    ASSERT_EQ(*sweep2, (std::vector<int>{9, 10}));
    e.Lease(10, "a", lease);
    EXPECT_EQ(lease.chunks, (std::vector<int>{1, 4}));
    EXPECT_EQ(e.PreferredWorker(10), "a");
    ASSERT_TRUE(e.Merge(9, {.sweeps = LitChunks(2, {0, 2, 3}, 5)}).ok());
    ASSERT_TRUE(e.Merge(10, {.sweeps = LitChunks(2, {1, 4}, 5)}).ok());
    absl::StatusOr<std::vector<int>> sweep3 = e.Publish(false, "h3");
    ASSERT_TRUE(sweep3.ok()) << sweep3.status();
    ASSERT_EQ(sweep3->size(), 1u) << "one worker holds every chunk";
    e.Lease(sweep3->front(), "a", lease);
    EXPECT_EQ(lease.chunks, (std::vector<int>{0, 1, 2, 3, 4}));
}

// A task taken again by "b" after its owner "a" was lost mid-task (the same task: its second
// lease does not move the chunks) gives them to "b" with its result (takes_over, which the
// scheduler sets when the owner is gone), and the next sweep's task of them goes to "b", not
// to a third worker that would compute the rows again. A straggler's copy that wins while the
// owner lives (no takes_over) leaves the chunks with their owner.
TEST(SweepExecution, ChunksGoToTheWorkerThatTookOverTheirTask) {
    const std::unique_ptr<SweepExecution> made = TwoTileSweeps(3);
    ASSERT_TRUE(made);
    SweepExecution& e = *made;
    const std::vector<int> sweep0 = e.Start();
    ASSERT_EQ(sweep0.size(), 3u);
    TaskAssignment lease;
    const std::vector<std::string> owner = {"a", "b", "c"};
    for (int c = 0; c < 3; ++c) {
        e.Lease(sweep0[size_t(c)], owner[size_t(c)], lease);
        if (c == 0) e.Lease(sweep0[0], "b", lease);  // "a" lost: the retry goes to "b"
        EXPECT_EQ(e.PreferredWorker(sweep0[size_t(c)]), owner[size_t(c)]);
        if (c == 2) e.Lease(sweep0[2], "b", lease);  // a straggler's copy; "c" lives
        const std::string takes_over = c == 0 ? "b" : "";
        ASSERT_TRUE(
            e.Merge(sweep0[size_t(c)], {.sweeps = LitChunks(0, {c}, 3), .takes_over = takes_over})
                .ok());
    }
    absl::StatusOr<std::vector<int>> sweep1 = e.Publish(false, "h1");
    ASSERT_TRUE(sweep1.ok()) << sweep1.status();
    ASSERT_EQ(sweep1->size(), 2u);
    EXPECT_EQ(e.PreferredWorker((*sweep1)[0]), "b");
    e.Lease((*sweep1)[0], "b", lease);
    EXPECT_EQ(lease.chunks, (std::vector<int>{0, 1}));
    EXPECT_EQ(e.PreferredWorker((*sweep1)[1]), "c");
}

// Display tiles of few samples are widened until a task holds 2^18 samples a pass, up to the
// farm's tile limit (lower with AOVs); tiles of enough samples stay as asked.
TEST(SweepExecution, WidensTheDisplayTilesOfCheapTasks) {
    auto tile = [](RenderPlanSettings plan, uint32_t aovs) {
        return SweepExecution::DisplayPlan(plan, aovs).tile;
    };
    EXPECT_EQ(tile({256, 256, 16, 32, 1}, 0), 128);  // 128^2 x 16 = 2^18
    EXPECT_EQ(tile({256, 256, 16, 32, 4}, 0), kMaxFarmTile);
    EXPECT_EQ(tile({256, 256, 16, 32, 4}, 1), kMaxFarmAovTile);
    EXPECT_EQ(tile({256, 256, 256, 32, 1}, 0), 32);
    EXPECT_EQ(tile({256, 256, 64, 24, 1}, 0), 96);
    EXPECT_EQ(tile({256, 256, 1, 150, 1}, 0), kMaxFarmTile);
    const RenderPlanSettings plan{64, 48, 16, 32, 1};
    absl::StatusOr<std::unique_ptr<SweepExecution>> made =
        SweepExecution::Make(plan, RadiositySettings(), MakeMemoryTileStore);
    ASSERT_TRUE(made.ok()) << made.status();
    EXPECT_EQ((*made)->tasks_total(), 1) << "one 64x48 display task";
}

TEST(MakeJobExecution, ChoosesTheKindFromTheSpec) {
    JobSpec spec;
    spec.plan = {16, 16, 4, 8, 1};
    spec.method = "path";
    auto kind = [&] {
        absl::StatusOr<std::unique_ptr<JobExecution>> made =
            MakeJobExecution(spec, MakeMemoryTileStore);
        EXPECT_TRUE(made.ok()) << made.status();
        const JobExecution& execution = **made;
        return std::type_index(typeid(execution));
    };
    EXPECT_EQ(kind(), std::type_index(typeid(TileExecution)));
    spec.adaptive.target_error = 0.1;
    EXPECT_EQ(kind(), std::type_index(typeid(AdaptiveTileExecution)));
    spec.adaptive.target_error = 0;
    spec.method = "radiosity";
    spec.radiosity.solver = "jacobi";
    EXPECT_EQ(kind(), std::type_index(typeid(SweepExecution)));
    spec.radiosity.solver = "shooting";
    EXPECT_EQ(kind(), std::type_index(typeid(TileExecution)));
    spec.method = "light";
    EXPECT_EQ(kind(), std::type_index(typeid(SplatExecution)));
    absl::StatusOr<std::unique_ptr<JobExecution>> light =
        MakeJobExecution(spec, MakeMemoryTileStore);
    ASSERT_TRUE(light.ok());
    EXPECT_EQ((*light)->Publish(true, "x").status().code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace lf
