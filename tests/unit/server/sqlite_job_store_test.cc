// The SQLite job store and what the scheduler rebuilds from it after a crash: records round
// trip, done tasks come back merged and are not leased again, leases of the dead server are
// queued again, a job rendered but not written is handed back for its result, and a store that
// cannot write refuses the submission instead of losing it.
#include "lf/server/sqlite_job_store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "lease_results.h"
#include "lf/job/shot.h"
#include "lf/server/farm.h"
#include "lf/server/scheduler.h"
#include "test_dir.h"
#include "test_job_store.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class SqliteJobStoreTest : public ::testing::Test {
  protected:
    void SetUp() override { dir_ = lf::testing::FreshTestDir("lf_store"); }
    void TearDown() override { fs::remove_all(dir_); }

    std::unique_ptr<SqliteJobStore> OpenStore() { return lf::testing::OpenJobStore(dir_); }

    // A 16x16 image in 8x8 tiles, 4 spp in 2 passes: 8 tasks.
    static JobSpec Spec() {
        JobSpec spec;
        spec.name = "test";
        spec.plan = {16, 16, 4, 8, 2};
        return spec;
    }

    // A result whose pixels depend on the task, so a wrong merge shows in the image.
    static TileSums Result(const TaskAssignment& lease) {
        TileSums sums = testing::UniformResult(lease, Rgb(0.1f * float(lease.task.index + 1)));
        sums.stats.samples = sums.pixels.size() * (lease.task.sample_end - lease.task.sample_begin);
        return sums;
    }

    static void CompleteAll(Scheduler& scheduler, const std::string& worker) {
        while (std::optional<TaskAssignment> lease = scheduler.LeaseTask(worker)) {
            ASSERT_TRUE(scheduler.Complete(lease->lease_id, worker, Result(*lease)).ok());
        }
    }

    // Submits a job and merges every task, the last (its completion `last`: the job rendered)
    // while the store fails its writes (FailingStore::fail, true only for that one).
    static void RenderWithTheLastRecordFailing(Scheduler& scheduler, bool& fail,
                                               std::optional<Scheduler::Completion>& last) {
        ASSERT_TRUE(scheduler.Submit(Spec()).ok());
        std::vector<TaskAssignment> leases;
        while (std::optional<TaskAssignment> l = scheduler.LeaseTask("w")) leases.push_back(*l);
        ASSERT_GE(leases.size(), 2u);
        for (size_t i = 0; i + 1 < leases.size(); ++i) {
            ASSERT_TRUE(scheduler.Complete(leases[i].lease_id, "w", Result(leases[i])).ok());
        }
        fail = true;
        absl::StatusOr<Scheduler::Completion> done =
            scheduler.Complete(leases.back().lease_id, "w", Result(leases.back()));
        ASSERT_TRUE(done.ok()) << done.status();
        ASSERT_TRUE(done->job_rendered);
        ASSERT_TRUE(done->unrecorded.has_value());
        ASSERT_EQ(done->unrecorded->task, leases.back().task.index);
        fail = false;
        last = *done;
    }

    static std::vector<float> Pixels(const Scheduler& scheduler, const std::string& id) {
        absl::StatusOr<Scheduler::JobImage> snapshot = scheduler.Snapshot(id);
        EXPECT_TRUE(snapshot.ok()) << snapshot.status();
        return *snapshot->image.FindChannel("R");
    }

    fs::path dir_;
};

TEST_F(SqliteJobStoreTest, RecordsRoundTripThroughAReopen) {
    JobRecord job;
    job.id = "job-1";
    job.seq = 7;
    job.spec = Spec();
    job.spec.scene = {"scene.json", "ab", 12};
    job.spec.files = {{"mesh.obj", "cd", 34}};
    job.spec.seed = 5;
    job.spec.max_depth = 3;
    job.spec.priority = -2;
    job.spec.scene_hash = "hash";
    job.spec.adaptive = {0.03, 120, 512};
    job.spec.radiosity.max_patches = 999;
    job.spec.radiosity.form = "hierarchical";
    job.spec.radiosity.link_error = 2.5e-4;
    job.state = JobState::kFailed;
    job.error = "why";
    job.submitted = absl::FromUnixMicros(1'000'001);
    job.started = absl::FromUnixMicros(1'000'002);
    job.tasks_total = 8;
    job.tasks_done = 3;
    job.retries = 2;
    job.tasks_leased = 6;
    job.stats = {10, 20, 1};
    job.result_path = "/r.exr";
    ASSERT_TRUE(OpenStore()->Put(job).ok());

    const absl::StatusOr<JobRecord> back = OpenStore()->Get("job-1");
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->seq, 7u);
    EXPECT_EQ(back->spec.scene.hash, "ab");
    ASSERT_EQ(back->spec.files.size(), 1u);
    EXPECT_EQ(back->spec.files[0].path, "mesh.obj");
    EXPECT_EQ(back->spec.plan.passes, 2);
    EXPECT_EQ(back->spec.priority, -2);
    EXPECT_EQ(back->spec.adaptive.target_error, 0.03);
    EXPECT_EQ(back->spec.adaptive.time_limit, 120);
    EXPECT_EQ(back->spec.adaptive.max_spp, 512u);
    EXPECT_EQ(back->spec.radiosity.max_patches, 999);
    EXPECT_EQ(back->spec.radiosity.form, "hierarchical");
    EXPECT_EQ(back->spec.radiosity.link_error, 2.5e-4);
    EXPECT_EQ(back->state, JobState::kFailed);
    EXPECT_EQ(back->error, "why");
    EXPECT_EQ(back->started, job.started);
    EXPECT_EQ(back->finished, absl::InfinitePast());
    EXPECT_EQ(back->tasks_leased, 6);
    EXPECT_EQ(back->stats.rays, 20u);
    EXPECT_EQ(back->result_path, "/r.exr");
    EXPECT_EQ(OpenStore()->Get("job-2").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(SqliteJobStoreTest, RestartKeepsDoneTasksAndQueuesTheRest) {
    // The same job without a crash, for the expected pixels.
    InMemoryJobStore memory;
    Scheduler reference({}, memory);
    const std::string ref_id = *reference.Submit(Spec());
    CompleteAll(reference, "w");
    const std::vector<float> expected = Pixels(reference, ref_id);

    std::string id, other;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler before({}, *store);
        id = *before.Submit(Spec());
        other = *before.Submit(Spec());  // never started
        for (int i = 0; i < 3; ++i) {
            std::optional<TaskAssignment> lease = before.LeaseTask("w");
            ASSERT_TRUE(before.Complete(lease->lease_id, "w", Result(*lease)).ok());
        }
        ASSERT_TRUE(before.LeaseTask("w"));  // leased when the server dies
    }                                        // the crash: nothing more is written

    std::unique_ptr<SqliteJobStore> store = OpenStore();
    Scheduler after({}, *store);
    absl::StatusOr<std::vector<Scheduler::JobRun>> rendered = after.Recover();
    ASSERT_TRUE(rendered.ok()) << rendered.status();
    EXPECT_TRUE(rendered->empty());
    EXPECT_EQ(after.Get(id)->tasks_done, 3);
    EXPECT_EQ(after.Get(id)->tasks_running, 0);
    EXPECT_EQ(after.Get(id)->state, JobState::kRunning);
    int leased = 0;
    while (std::optional<TaskAssignment> lease = after.LeaseTask("w")) {
        if (lease->job_id != id) break;
        EXPECT_GE(lease->task.index, 3) << "a done task was leased again";
        ++leased;
        absl::StatusOr<Scheduler::Completion> done =
            after.Complete(lease->lease_id, "w", Result(*lease));
        ASSERT_TRUE(done.ok()) << done.status();
        if (done->job_rendered) {
            EXPECT_EQ(Pixels(after, id), expected);
        }
    }
    EXPECT_EQ(leased, 5);
    // The three recorded with their results, and the five since: the lease the server died
    // with was not written (a lease is not, but for a job's first, and its count goes with the
    // next write).
    EXPECT_EQ(after.Get(id)->tasks_leased, 3 + 5);
    EXPECT_EQ(after.Get(other)->state, JobState::kRunning);  // its first task is leased now

    // Submission order survives: a new job is the newest.
    const std::string newest = *after.Submit(Spec());
    EXPECT_EQ(after.List()->front().id, newest);
    EXPECT_NE(newest, id);
}

// Issue 27: a restart showed the tasks done before it with 0 attempts, no worker and no duration.
TEST_F(SqliteJobStoreTest, RestartKeepsTheDoneTasksAttemptsWorkerAndDuration) {
    absl::Time now = absl::FromUnixSeconds(1'000'000);
    const Scheduler::Clock clock = [&now] { return now; };
    std::string id;
    std::vector<TaskStatus> before_restart;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler before({}, *store, clock);
        id = *before.Submit(Spec());
        // One task fails on the first worker, and is done by the second.
        std::optional<TaskAssignment> failed = before.LeaseTask("node1/host-11");
        ASSERT_TRUE(failed);
        now += absl::Seconds(1);
        ASSERT_TRUE(
            before.Fail(failed->lease_id, "node1/host-11", "flaky", FailureKind::kTaskError).ok());
        for (int i = 0; i < 4; ++i) {
            std::optional<TaskAssignment> lease = before.LeaseTask("node1/host-12");
            ASSERT_TRUE(lease);
            now += absl::Seconds(2 + i);
            ASSERT_TRUE(before.Complete(lease->lease_id, "node1/host-12", Result(*lease)).ok());
        }
        before_restart = *before.Tasks(id);
    }
    int done = 0, retried = 0;
    for (const TaskStatus& task : before_restart) {
        if (task.state != TaskStatus::State::kDone) continue;
        ++done;
        retried += task.attempts == 2;
    }
    ASSERT_EQ(done, 4);

    std::unique_ptr<SqliteJobStore> store = OpenStore();
    now += absl::Minutes(1);
    Scheduler after({}, *store, clock);
    ASSERT_TRUE(after.Recover().ok());
    const std::vector<TaskStatus> tasks = *after.Tasks(id);
    ASSERT_EQ(tasks.size(), before_restart.size());
    for (const TaskStatus& was : before_restart) {
        if (was.state != TaskStatus::State::kDone) continue;
        SCOPED_TRACE(was.index);
        const TaskStatus& is = tasks[size_t(was.index)];
        EXPECT_EQ(is.state, TaskStatus::State::kDone);
        EXPECT_EQ(is.attempts, was.attempts);
        EXPECT_EQ(is.failures, was.failures);
        EXPECT_EQ(is.worker, "node1/host-12");
        EXPECT_EQ(is.leased, was.leased);
        EXPECT_EQ(is.finished, was.finished);
        EXPECT_GE(is.duration, absl::Seconds(2));
        EXPECT_EQ(is.duration, was.duration);
    }
    EXPECT_EQ(retried, 1) << "the failed task's second lease is counted";
}

TEST_F(SqliteJobStoreTest, JobRenderedButNotWrittenIsHandedBackAfterARestart) {
    std::string id;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler before({}, *store);
        id = *before.Submit(Spec());
        CompleteAll(before, "w");  // the server dies before Finish
    }
    std::unique_ptr<SqliteJobStore> store = OpenStore();
    Scheduler after({}, *store);
    absl::StatusOr<std::vector<Scheduler::JobRun>> rendered = after.Recover();
    ASSERT_TRUE(rendered.ok()) << rendered.status();
    ASSERT_EQ(rendered->size(), 1u);
    EXPECT_EQ(rendered->front().job_id, id);
    EXPECT_FALSE(after.LeaseTask("w"));
    after.Finish(rendered->front(), std::string("/results/x.exr"));
    EXPECT_EQ(after.Get(id)->state, JobState::kSucceeded);
    EXPECT_TRUE(store->TaskResults(id)->empty()) << "an ended job keeps no task results";
}

// Job management (issue 30): a failed job keeps its task results, so that a requeue after a
// restart merges them again (the Recover path) and renders only the rest, to the image of a
// job that never failed.
TEST_F(SqliteJobStoreTest, RequeuedFailedJobRendersOnFromItsRecordedResultsAfterARestart) {
    JobSpec spec = Spec();  // 8 tasks
    spec.max_attempts = 1;
    std::string id, whole;
    std::vector<float> expected;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler before({}, *store);
        whole = *before.Submit(Spec());
        CompleteAll(before, "w");
        expected = Pixels(before, whole);
        id = *before.Submit(spec);
        for (int i = 0; i < 3; ++i) {
            const TaskAssignment lease = *before.LeaseTask("w");
            ASSERT_TRUE(before.Complete(lease.lease_id, "w", Result(lease)).ok());
        }
        const TaskAssignment failing = *before.LeaseTask("w");
        ASSERT_TRUE(before.Fail(failing.lease_id, "w", "no GPU", FailureKind::kTaskError).ok());
        ASSERT_EQ(before.Get(id)->state, JobState::kFailed);
        EXPECT_EQ(store->TaskResults(id)->size(), 3u) << "a failed job keeps its task results";
    }
    std::unique_ptr<SqliteJobStore> store = OpenStore();
    Scheduler after({}, *store);
    ASSERT_TRUE(after.Recover().ok());
    EXPECT_EQ(after.Get(id)->state, JobState::kFailed);  // stays failed until requeued
    absl::StatusOr<Scheduler::Requeued> requeued = after.RequeueJob(id);
    ASSERT_TRUE(requeued.ok()) << requeued.status();
    EXPECT_EQ(requeued->record.state, JobState::kQueued);
    EXPECT_EQ(requeued->record.error, "");
    EXPECT_EQ(requeued->record.tasks_done, 3);
    EXPECT_FALSE(requeued->rendered);
    EXPECT_EQ(store->Get(id)->state, JobState::kQueued);  // durable
    int leased = 0;
    while (std::optional<TaskAssignment> lease = after.LeaseTask("w")) {
        ++leased;
        ASSERT_TRUE(after.Complete(lease->lease_id, "w", Result(*lease)).ok());
    }
    EXPECT_EQ(leased, 5);
    EXPECT_EQ(Pixels(after, id), expected);
    after.Finish({id, requeued->run}, std::string("/results/x.exr"));
    EXPECT_EQ(after.Get(id)->state, JobState::kSucceeded);
    EXPECT_TRUE(store->TaskResults(id)->empty()) << "a succeeded job keeps no task results";
    EXPECT_EQ(after.RequeueJob(id).status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(after.RequeueJob("job-none").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(SqliteJobStoreTest, SubmissionRetriedWithItsRequestIdGetsTheSameJob) {
    JobSpec spec = Spec();
    spec.request_id = "req-1";
    std::string id;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler before({}, *store);
        id = *before.Submit(spec);
        EXPECT_EQ(*before.Submit(spec), id);  // the answer was lost, the client retries
    }
    std::unique_ptr<SqliteJobStore> store = OpenStore();
    Scheduler after({}, *store);
    ASSERT_TRUE(after.Recover().ok());
    EXPECT_EQ(*after.Submit(spec), id) << "a retry after a restart";
    spec.request_id = "req-2";
    EXPECT_NE(*after.Submit(spec), id);
    EXPECT_EQ(after.List()->size(), 2u);
}

// A store whose writes, or reads, fail on demand, as on a full disk or a damaged database.
class FailingStore : public InMemoryJobStore {
  public:
    bool fail = false, fail_reads = false;
    static constexpr uint64_t kFailed = ~uint64_t(0);  // not one of InMemoryJobStore's tickets
    uint64_t QueuePut(const JobRecord& job) override {
        return fail ? kFailed : InMemoryJobStore::QueuePut(job);
    }
    uint64_t QueueTaskDone(const JobRecord& job, int, std::string, const TaskHistory&) override {
        return QueuePut(job);
    }
    absl::Status WaitDurable(uint64_t ticket) override {
        return ticket == kFailed ? absl::ResourceExhaustedError("job store: disk full")
                                 : InMemoryJobStore::WaitDurable(ticket);
    }
    absl::StatusOr<std::vector<JobRecord>> List(const JobQuery& query) const override {
        if (fail_reads) return absl::DataLossError("job store: database disk image is malformed");
        return InMemoryJobStore::List(query);
    }
};

TEST_F(SqliteJobStoreTest, StoreThatCannotListFailsRecoveryInsteadOfStartingEmpty) {
    FailingStore store;
    {
        Scheduler before({}, store);
        ASSERT_TRUE(before.Submit(Spec()).ok());
    }
    store.fail_reads = true;
    Scheduler after({}, store);
    const absl::StatusOr<std::vector<Scheduler::JobRun>> rendered = after.Recover();
    EXPECT_EQ(rendered.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_NE(rendered.status().message().find("malformed"), std::string_view::npos);
    EXPECT_EQ(after.List().status().code(), absl::StatusCode::kDataLoss) << "nor lists nothing";
}

// A stored job this build cannot take up (here a shot over the frame limit, as a store written by
// an older build could hold) fails alone, naming why; the server starts with the other jobs.
TEST_F(SqliteJobStoreTest, StoredJobThatCannotBeTakenUpFailsAloneAndTheRestRecover) {
    std::string good, bad;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler before({}, *store);
        good = *before.Submit(Spec());
        bad = *before.Submit(Spec());
        JobRecord record = *store->Get(bad);
        record.spec.shot.frames = FrameRange{1, kMaxShotFrames + 1, 1};
        ASSERT_TRUE(store->Put(record).ok());
    }
    std::unique_ptr<SqliteJobStore> store = OpenStore();
    Scheduler after({}, *store);
    const absl::StatusOr<std::vector<Scheduler::JobRun>> rendered = after.Recover();
    ASSERT_TRUE(rendered.ok()) << rendered.status();
    const JobRecord failed = *after.Get(bad);
    EXPECT_EQ(failed.state, JobState::kFailed);
    EXPECT_NE(failed.error.find("cannot be taken up after the coordinator restarted"),
              std::string::npos)
        << failed.error;
    EXPECT_NE(failed.error.find(std::to_string(kMaxShotFrames)), std::string::npos) << failed.error;
    EXPECT_EQ(store->Get(bad)->state, JobState::kFailed) << "the failure is stored";
    CompleteAll(after, "w");
    EXPECT_EQ(after.Get(good)->tasks_done, 8);
}

TEST_F(SqliteJobStoreTest, StoreThatCannotWriteRefusesWithoutHarmingEarlierJobs) {
    FailingStore store;
    Scheduler scheduler({}, store);
    const std::string done = *scheduler.Submit(Spec());
    CompleteAll(scheduler, "w");
    scheduler.Finish({done, scheduler.Snapshot(done)->run}, std::string("/results/x.exr"));
    const std::string running = *scheduler.Submit(Spec());
    std::optional<TaskAssignment> lease = scheduler.LeaseTask("w");

    store.fail = true;
    const absl::StatusOr<std::string> refused = scheduler.Submit(Spec());
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kResourceExhausted);
    EXPECT_NE(refused.status().message().find("disk full"), std::string_view::npos);
    EXPECT_EQ(scheduler.List()->size(), 2u);
    // A result that cannot be recorded is refused with the reason, not acknowledged.
    absl::StatusOr<Scheduler::Completion> result =
        scheduler.Complete(lease->lease_id, "w", Result(*lease));
    EXPECT_EQ(result.status().code(), absl::StatusCode::kResourceExhausted);
    EXPECT_EQ(scheduler.Get(running)->state, JobState::kFailed) << "watchers learn it ended";
    EXPECT_NE(scheduler.Get(running)->error.find("disk full"), std::string::npos);
    store.fail = false;
    EXPECT_EQ(scheduler.Get(done)->state, JobState::kSucceeded);
    EXPECT_EQ(store.Get(running)->state, JobState::kRunning) << "so it runs after a restart";
}

// The result that renders the job is answered by AwaitRecorded (the farm writes the image
// meanwhile): a record that fails there fails the job, which has not ended yet.
TEST_F(SqliteJobStoreTest, LastResultThatCannotBeRecordedFailsTheJobBeforeItEnds) {
    FailingStore store;
    Scheduler scheduler({}, store);
    std::optional<Scheduler::Completion> last;
    ASSERT_NO_FATAL_FAILURE(RenderWithTheLastRecordFailing(scheduler, store.fail, last));
    const std::string id = last->job_id;
    EXPECT_EQ(scheduler.Get(id)->state, JobState::kRunning) << "not failed before the wait";
    const absl::Status recorded = scheduler.AwaitRecorded(*last);
    EXPECT_EQ(recorded.code(), absl::StatusCode::kResourceExhausted);
    EXPECT_EQ(scheduler.Get(id)->state, JobState::kFailed);
    EXPECT_NE(scheduler.Get(id)->error.find(
                  absl::StrCat("recording the result of task ", last->unrecorded->task, ": ")),
              std::string::npos)
        << scheduler.Get(id)->error;
}

// The job cancelled and requeued while the last result's record was awaited is another run: that
// record failing does not fail it, although it has rendered the task again meanwhile, and the
// earlier run's Finish (its image written meanwhile) does not end it.
TEST_F(SqliteJobStoreTest, WhatIsDecidedForAnEndedRunLeavesTheJobQueuedAgainAlone) {
    FailingStore store;
    Scheduler scheduler({}, store);
    std::optional<Scheduler::Completion> last;
    ASSERT_NO_FATAL_FAILURE(RenderWithTheLastRecordFailing(scheduler, store.fail, last));
    ASSERT_TRUE(scheduler.Cancel(last->job_id).ok());
    const std::string id = last->job_id;
    const absl::StatusOr<Scheduler::Requeued> requeued = scheduler.RequeueJob(id);
    ASSERT_TRUE(requeued.ok()) << requeued.status();
    EXPECT_NE(requeued->run, last->run);
    EXPECT_EQ(scheduler.Snapshot(id)->run, requeued->run);
    std::optional<Scheduler::Completion> again;
    while (std::optional<TaskAssignment> l = scheduler.LeaseTask("w")) {
        absl::StatusOr<Scheduler::Completion> done =
            scheduler.Complete(l->lease_id, "w", Result(*l));
        ASSERT_TRUE(done.ok()) << done.status();
        if (done->job_rendered) again = *done;
    }
    ASSERT_TRUE(again.has_value()) << "the requeued run renders the unrecorded task again";
    EXPECT_EQ(scheduler.AwaitRecorded(*last).code(), absl::StatusCode::kResourceExhausted);
    EXPECT_EQ(scheduler.Get(id)->state, JobState::kRunning) << scheduler.Get(id)->error;
    scheduler.Finish({id, last->run}, std::string("/results/old.exr"));
    EXPECT_EQ(scheduler.Get(id)->state, JobState::kRunning);
    ASSERT_TRUE(scheduler.AwaitRecorded(*again).ok());
    scheduler.Finish({id, again->run}, std::string("/results/x.exr"));
    EXPECT_EQ(scheduler.Get(id)->state, JobState::kSucceeded);
    EXPECT_EQ(scheduler.Get(id)->result_path, "/results/x.exr");
}

TEST_F(SqliteJobStoreTest, UnusableDataDirIsAClearError) {
    std::ofstream(dir_ / "file") << "x";
    FarmOptions options;
    options.data_dir = (dir_ / "file" / "data").string();
    absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
    ASSERT_FALSE(farm.ok());
    EXPECT_NE(farm.status().message().find(options.data_dir), std::string_view::npos)
        << farm.status();
}

// An adaptive job's passes are appended as results arrive; after a crash, replaying the recorded
// results in index order plans the same passes again, so the job ends with the same pixels.
TEST_F(SqliteJobStoreTest, RestartReplaysAnAdaptiveJobsPasses) {
    JobSpec spec = Spec();
    spec.plan.passes = 1;
    spec.adaptive = {.target_error = 0.1, .time_limit = 0, .max_spp = 64};
    // Every pixel's halves read 0.4 and 0.6: relative error 0.2 at any count, so each tile goes
    // 4 -> 18 -> 64 samples.
    auto halves = [](const TaskAssignment& lease) {
        TileSums sums(lease.task.rect);
        for (PixelSums& p : sums.pixels) {
            for (uint64_t s = lease.task.sample_begin; s < lease.task.sample_end; ++s) {
                p.Add(s, Rgb(s % 2 ? 0.6f : 0.4f));
            }
        }
        return sums;
    };
    InMemoryJobStore memory;
    Scheduler reference({}, memory);
    const std::string ref_id = *reference.Submit(spec);
    while (std::optional<TaskAssignment> lease = reference.LeaseTask("w")) {
        ASSERT_TRUE(reference.Complete(lease->lease_id, "w", halves(*lease)).ok());
    }
    EXPECT_EQ(reference.Get(ref_id)->tasks_done, 12);
    const std::vector<float> expected = Pixels(reference, ref_id);

    std::string id;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler before({}, *store);
        id = *before.Submit(spec);
        for (int i = 0; i < 6; ++i) {
            std::optional<TaskAssignment> lease = before.LeaseTask("w");
            ASSERT_TRUE(before.Complete(lease->lease_id, "w", halves(*lease)).ok());
        }
        // The 4 first passes, 4 second ones, and the third passes of the 2 tiles done twice.
        EXPECT_EQ(before.Get(id)->tasks_total, 10);
        ASSERT_TRUE(before.LeaseTask("w"));  // leased when the server dies
    }
    std::unique_ptr<SqliteJobStore> store = OpenStore();
    Scheduler after({}, *store);
    ASSERT_TRUE(after.Recover().ok());
    EXPECT_EQ(after.Get(id)->tasks_done, 6);
    EXPECT_EQ(after.Get(id)->tasks_total, 10);
    int leased = 0;
    bool rendered = false;
    while (std::optional<TaskAssignment> lease = after.LeaseTask("w")) {
        ++leased;
        absl::StatusOr<Scheduler::Completion> done =
            after.Complete(lease->lease_id, "w", halves(*lease));
        ASSERT_TRUE(done.ok()) << done.status();
        rendered |= done->job_rendered;
    }
    EXPECT_TRUE(rendered);
    EXPECT_EQ(leased, 6);
    EXPECT_EQ(Pixels(after, id), expected);
}

// History (issue 30): a row a merged task and an ended job, summed per owner and per worker,
// filtered by time and owner, kept when the jobs are deleted, pruned when too old.
class SqliteJobStoreStatsTest : public SqliteJobStoreTest {
  protected:
    static JobRecord Job(const std::string& id, const std::string& owner, JobState state,
                         absl::Time finished = absl::InfinitePast()) {
        JobRecord job{.id = id, .seq = uint64_t(id.back()), .spec = Spec()};
        job.spec.owner = owner;
        job.state = state;
        job.finished = finished;
        return job;
    }
    static TaskHistory Done(const std::string& worker, absl::Time finished, TaskTimes times,
                            uint64_t samples) {
        TaskHistory h{.attempts = 1, .worker = worker, .finished = finished};
        h.times = times;
        h.samples = samples;
        return h;
    }
    static void TaskDone(SqliteJobStore& store, const JobRecord& job, int task,
                         const TaskHistory& h) {
        ASSERT_TRUE(store.WaitDurable(store.QueueTaskDone(job, task, "sums", h)).ok());
    }

    const absl::Time t0_ = absl::Now() - absl::Hours(1);
};

TEST_F(SqliteJobStoreStatsTest, TasksAndEndedJobsAddUpPerOwnerAndWorkerAndOutliveDeletion) {
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        const JobRecord a = Job("job-a", "alice", JobState::kRunning);
        const JobRecord b = Job("job-b", "bob", JobState::kRunning);
        TaskDone(*store, a, 0, Done("w1", t0_ + absl::Seconds(10), {1, 2}, 100));
        TaskDone(*store, a, 1, Done("w2", t0_ + absl::Seconds(20), {3, 4}, 50));
        TaskDone(*store, b, 0, Done("w1", t0_ + absl::Seconds(30), {5, 6}, 10));
        // Older than kept: pruned when a job ends.
        TaskDone(*store, b, 1, Done("w1", absl::Now() - absl::Hours(401 * 24), {100, 100}, 1));
        ASSERT_TRUE(
            store->Put(Job("job-a", "alice", JobState::kSucceeded, t0_ + absl::Seconds(40))).ok());
        JobRecord failed = Job("job-b", "bob", JobState::kFailed, t0_ + absl::Seconds(50));
        failed.worker_failures = {{"w2", 2, "boom"}};
        ASSERT_TRUE(store->Put(failed).ok());
        // Written again as it is (a later write of an ended record): counted once.
        ASSERT_TRUE(store->Put(failed).ok());
        ASSERT_TRUE(store->Put(Job("job-c", "alice", JobState::kQueued)).ok());
        // Requeued after it was cancelled: active, not cancelled.
        ASSERT_TRUE(
            store->Put(Job("job-d", "alice", JobState::kCancelled, t0_ + absl::Seconds(45))).ok());
        ASSERT_TRUE(store->Put(Job("job-d", "alice", JobState::kQueued)).ok());
        ASSERT_TRUE(store->Delete("job-a").ok());
        ASSERT_TRUE(store->Delete("job-b").ok());
    }
    std::unique_ptr<SqliteJobStore> store = OpenStore();  // across a restart

    absl::StatusOr<FarmStats> all = store->Stats({});
    ASSERT_TRUE(all.ok()) << all.status();
    EXPECT_EQ(all->since, absl::InfinitePast());
    ASSERT_EQ(all->owners.size(), 2u);
    EXPECT_EQ(all->owners[0], (OwnerStats{"alice", 1, 0, 0, 2, 2, 150, {4, 6}}));
    EXPECT_EQ(all->owners[1], (OwnerStats{"bob", 0, 1, 0, 0, 1, 10, {5, 6}}));
    ASSERT_EQ(all->workers.size(), 2u);
    EXPECT_EQ(all->workers[0], (WorkerStats{"w1", 2, 0, {6, 8}}));
    EXPECT_EQ(all->workers[1], (WorkerStats{"w2", 1, 2, {3, 4}}));

    const absl::Time since = t0_ + absl::Seconds(25);
    absl::StatusOr<FarmStats> recent = store->Stats({.since = since});
    ASSERT_TRUE(recent.ok()) << recent.status();
    EXPECT_EQ(recent->since, since);
    ASSERT_EQ(recent->owners.size(), 2u);
    EXPECT_EQ(recent->owners[0], (OwnerStats{"alice", 1, 0, 0, 2, 0, 0, {}}));
    EXPECT_EQ(recent->owners[1], (OwnerStats{"bob", 0, 1, 0, 0, 1, 10, {5, 6}}));
    ASSERT_EQ(recent->workers.size(), 2u);
    EXPECT_EQ(recent->workers[0], (WorkerStats{"w1", 1, 0, {5, 6}}));
    EXPECT_EQ(recent->workers[1], (WorkerStats{"w2", 0, 2, {}}));

    // One owner's: the workers' rows of their tasks only (w2's failures were in bob's job).
    absl::StatusOr<FarmStats> alice = store->Stats({.owner = "alice"});
    ASSERT_TRUE(alice.ok()) << alice.status();
    ASSERT_EQ(alice->owners.size(), 1u);
    EXPECT_EQ(alice->owners[0].owner, "alice");
    ASSERT_EQ(alice->workers.size(), 2u);
    EXPECT_EQ(alice->workers[0], (WorkerStats{"w1", 1, 0, {1, 2}}));
    EXPECT_EQ(alice->workers[1], (WorkerStats{"w2", 1, 0, {3, 4}}));
}

TEST_F(SqliteJobStoreStatsTest, AVersion3StoreOpensAndGainsTheHistoryTablesWithItsEndedJobs) {
    const std::string path = (dir_ / "jobs.db").string();
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        ASSERT_TRUE(store->Put(Job("job-a", "alice", JobState::kRunning)).ok());
        ASSERT_TRUE(store->Put(Job("job-b", "bob", JobState::kFailed, t0_)).ok());
    }
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db,
                           "DROP TABLE task_stats; DROP TABLE job_stats;"
                           " DROP TABLE worker_failure_stats; PRAGMA user_version = 3;",
                           nullptr, nullptr, nullptr),
              SQLITE_OK)
        << sqlite3_errmsg(db);
    sqlite3_close(db);

    std::unique_ptr<SqliteJobStore> store = OpenStore();
    ASSERT_TRUE(store->Get("job-a").ok());
    TaskDone(*store, *store->Get("job-a"), 0, Done("w1", t0_, {1, 2}, 3));
    absl::StatusOr<FarmStats> stats = store->Stats({});
    ASSERT_TRUE(stats.ok()) << stats.status();
    ASSERT_EQ(stats->owners.size(), 2u);
    EXPECT_EQ(stats->owners[0], (OwnerStats{"alice", 0, 0, 0, 1, 1, 3, {1, 2}}));
    // Ended before the upgrade: counted by its state, without tasks.
    EXPECT_EQ(stats->owners[1], (OwnerStats{"bob", 0, 1, 0, 0, 0, 0, {}}));
}

}  // namespace
}  // namespace lf
