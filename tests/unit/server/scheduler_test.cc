// The task state machine with a fake clock: priority then age, leases that heartbeats keep
// alive and that expire otherwise, retries on other workers, three strikes, cancel, and
// results that arrive late or twice.
#include "lf/server/scheduler.h"

#include <gtest/gtest.h>

#include <future>
#include <thread>

#include "absl/strings/str_cat.h"
#include "lease_results.h"
#include "lf/server/worker_registry.h"

namespace lf {
namespace {

class SchedulerTest : public ::testing::Test {
  protected:
    SchedulerTest() : scheduler_(Options(), store_, [this] { return now_; }) {}

    static SchedulerOptions Options() {
        SchedulerOptions o;
        o.lease = absl::Seconds(10);
        return o;
    }

    // A 16x16 image in 8x8 tiles, 4 spp in 2 passes: 8 tasks.
    std::string Submit(int priority, int tile = 8, int passes = 2) {
        JobSpec spec;
        spec.name = "test";
        spec.plan = {16, 16, 4, tile, passes};
        spec.priority = priority;
        absl::StatusOr<std::string> id = scheduler_.Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        now_ += absl::Milliseconds(1);
        return *id;
    }

    static TileSums Result(const TaskAssignment& lease) {
        return testing::UniformResult(lease, Rgb(0.5f));
    }

    JobRecord Job(const std::string& id) { return *scheduler_.Get(id); }

    absl::Time now_ = absl::FromUnixSeconds(1'000'000);
    InMemoryJobStore store_;
    Scheduler scheduler_;
};

// The result of a sweep task of one chunk of a system of two unknowns, one a chunk, each
// gathering 1 from sweep 0 on.
SweepChunkResult LitChunk(const TaskAssignment& lease) {
    SweepChunkResult r;
    r.sweep = lease.sweep;
    r.chunk = lease.chunks.at(0);
    r.sides = 2;
    r.side_begin = r.chunk;
    r.change = {1};
    r.power = {1};
    r.input = {Rgb(lease.sweep == 0 ? 0 : 1)};
    r.output = {Rgb(1)};
    return r;
}

// A radiosity sweep task waits for the worker holding its chunks while that worker lives and
// may work on the job; one disabled (or blocklisted, or without the job's tags) never takes it,
// so another worker does instead of the job waiting forever.
TEST_F(SchedulerTest, ASweepTaskOfADisabledOwnerGoesToAnotherWorker) {
    JobSpec spec;
    spec.name = "sweeps";
    spec.plan = {16, 16, 4, 8, 1};
    spec.method = "radiosity";
    spec.radiosity.solver = "jacobi";
    spec.radiosity.sweep_tasks = 2;
    absl::StatusOr<std::string> id = scheduler_.Submit(spec);
    ASSERT_TRUE(id.ok()) << id.status();
    // Sweep 0: chunk 0 to "a", chunk 1 to "b"; one unknown a chunk, lit.
    for (const std::string worker : {"a", "b"}) {
        std::optional<TaskAssignment> lease = scheduler_.LeaseTask(worker);
        ASSERT_TRUE(lease && lease->sweep == 0) << worker;
        ASSERT_TRUE(scheduler_.CompleteSweep(lease->lease_id, worker, LitChunk(*lease)).ok())
            << worker;
    }
    scheduler_.Publish(*id, false, "h1");
    std::optional<TaskAssignment> mine = scheduler_.LeaseTask("a");
    ASSERT_TRUE(mine && mine->sweep == 1);
    EXPECT_EQ(mine->chunks, std::vector<int>{0});
    EXPECT_FALSE(scheduler_.LeaseTask("a")) << "b's task waits for b, which lives";
    scheduler_.SetWorkerControl("b", WorkerControl::kDisabled);
    std::optional<TaskAssignment> theirs = scheduler_.LeaseTask("a");
    ASSERT_TRUE(theirs && theirs->sweep == 1) << "b is disabled: a takes its task";
    EXPECT_EQ(theirs->chunks, std::vector<int>{1});
    // a's result of b's task makes a the chunk's owner (it holds its rows now): sweep 2 is one
    // task, of both chunks, for a.
    for (const TaskAssignment* lease : {&*mine, &*theirs}) {
        ASSERT_TRUE(scheduler_.CompleteSweep(lease->lease_id, "a", LitChunk(*lease)).ok());
    }
    scheduler_.Publish(*id, false, "h2");
    std::optional<TaskAssignment> both = scheduler_.LeaseTask("a");
    ASSERT_TRUE(both && both->sweep == 2);
    EXPECT_EQ(both->chunks, (std::vector<int>{0, 1}));
}

TEST_F(SchedulerTest, HigherPriorityFirstThenOlderFirst) {
    const std::string low = Submit(0), high_old = Submit(5), high_new = Submit(5);
    EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, high_old);
    for (int i = 0; i < 7; ++i) EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, high_old);
    EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, high_new);
    const std::string urgent = Submit(9);
    EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, urgent);
    EXPECT_EQ(Job(low).state, JobState::kQueued);
    EXPECT_EQ(Job(high_old).state, JobState::kRunning);
    EXPECT_EQ(Job(high_old).tasks_running, 8);
}

TEST_F(SchedulerTest, RaisedPriorityIsLeasedFirstAndRecorded) {
    const std::string first = Submit(0), second = Submit(0);
    EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, first);
    absl::StatusOr<JobRecord> raised = scheduler_.SetPriority(second, 3);
    ASSERT_TRUE(raised.ok()) << raised.status();
    EXPECT_EQ(raised->spec.priority, 3);
    EXPECT_EQ(store_.Get(second)->spec.priority, 3);  // saved, not only in memory
    for (int i = 0; i < 8; ++i) EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, second);
    EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, first);
    // Lowered below the other again: the other's queued tasks come first.
    ASSERT_TRUE(scheduler_.SetPriority(first, -1).ok());
    const std::string third = Submit(0);
    EXPECT_EQ(scheduler_.LeaseTask("w")->job_id, third);
}

TEST_F(SchedulerTest, PriorityOfAnEndedOrUnknownJobIsRefused) {
    const std::string id = Submit(0);
    ASSERT_TRUE(scheduler_.Cancel(id).ok());
    EXPECT_TRUE(absl::IsFailedPrecondition(scheduler_.SetPriority(id, 1).status()));
    EXPECT_TRUE(absl::IsNotFound(scheduler_.SetPriority("nope", 1).status()));
}

TEST_F(SchedulerTest, AllResultsInAnyOrderSucceedTheJob) {
    const std::string id = Submit(0);
    std::vector<TaskAssignment> leases;
    while (std::optional<TaskAssignment> l = scheduler_.LeaseTask("w")) leases.push_back(*l);
    ASSERT_EQ(leases.size(), 8u);
    uint64_t run = 0;
    for (size_t i = leases.size(); i-- > 0;) {
        absl::StatusOr<Scheduler::Completion> done =
            scheduler_.Complete(leases[i].lease_id, "w", Result(leases[i]));
        ASSERT_TRUE(done.ok()) << done.status();
        EXPECT_EQ(done->job_id, id);
        EXPECT_EQ(done->job_rendered, i == 0);
        run = done->run;
    }
    EXPECT_EQ(Job(id).tasks_done, 8);
    EXPECT_EQ(Job(id).stats.samples, 0u);  // the fake results carry no stats
    auto snapshot = scheduler_.Snapshot(id);
    ASSERT_TRUE(snapshot.ok());
    EXPECT_EQ((*snapshot->image.FindChannel("spp"))[0], 4.0f);
    EXPECT_EQ(snapshot->run, run);
    scheduler_.Finish({id, run}, std::string("/results/x.exr"));
    EXPECT_EQ(Job(id).state, JobState::kSucceeded);
    EXPECT_EQ(Job(id).result_path, "/results/x.exr");
    EXPECT_FALSE(scheduler_.LeaseTask("w").has_value());
}

TEST_F(SchedulerTest, HeartbeatsKeepALeaseAndSilenceLosesIt) {
    const std::string id = Submit(0);
    const TaskAssignment lease = *scheduler_.LeaseTask("a");
    for (int i = 0; i < 5; ++i) {
        now_ += absl::Seconds(8);
        EXPECT_TRUE(scheduler_.Heartbeat(lease.lease_id, "a"));
        EXPECT_EQ(scheduler_.ExpireLeases(), 0);
    }
    now_ += absl::Seconds(10);
    EXPECT_EQ(scheduler_.ExpireLeases(), 1);
    EXPECT_FALSE(scheduler_.Heartbeat(lease.lease_id, "a"));  // the worker is told to stop
    EXPECT_EQ(Job(id).retries, 1);
    EXPECT_EQ(Job(id).tasks_running, 0);
}

TEST_F(SchedulerTest, WorkersShowTheirTaskWhileLeasedAndGoWhenSilent) {
    const std::string id = Submit(0);
    const WorkerDescription about{"render-07", "ipv4:10.0.0.7:40000", "v1"};
    const TaskAssignment lease = *scheduler_.LeaseTask("a", absl::InfinitePast(), &about);
    now_ += absl::Seconds(2);
    std::vector<WorkerStatus> workers = scheduler_.Workers();
    ASSERT_EQ(workers.size(), 1u);
    EXPECT_EQ(workers[0].id, "a");
    EXPECT_EQ(workers[0].name, "render-07");
    EXPECT_EQ(workers[0].address, "ipv4:10.0.0.7:40000");
    EXPECT_EQ(workers[0].version, "v1");
    EXPECT_TRUE(workers[0].busy());
    EXPECT_EQ(workers[0].job_id, id);
    EXPECT_EQ(workers[0].task, lease.task.index);
    EXPECT_EQ(workers[0].since_seen, absl::Seconds(2));
    EXPECT_EQ(scheduler_.Load().workers_busy, 1);

    ASSERT_TRUE(scheduler_.Complete(lease.lease_id, "a", Result(lease)).ok());
    workers = scheduler_.Workers();
    ASSERT_EQ(workers.size(), 1u);
    EXPECT_FALSE(workers[0].busy());
    EXPECT_EQ(workers[0].since_seen, absl::ZeroDuration());  // the result counts as heard from
    EXPECT_EQ(scheduler_.Load().workers_busy, 0);
    EXPECT_EQ(scheduler_.Load().workers_live, 1);

    // Silent for a lease: no longer live, listed as offline (issue 30) until
    // forget_workers_after, then forgotten.
    now_ += absl::Seconds(10);
    workers = scheduler_.Workers();
    ASSERT_EQ(workers.size(), 1u);
    EXPECT_TRUE(workers[0].offline);
    EXPECT_EQ(scheduler_.Load().workers_live, 0);
    now_ += SchedulerOptions{}.forget_workers_after;
    EXPECT_TRUE(scheduler_.Workers().empty());
}

TEST_F(SchedulerTest, RetriedTaskGoesToAnotherWorkerWhenThereIsOne) {
    Submit(0);
    const TaskAssignment lease = *scheduler_.LeaseTask("a");
    scheduler_.LeaseTask("b");  // b is alive
    ASSERT_TRUE(
        scheduler_.Fail(lease.lease_id, "a", "out of memory", FailureKind::kTaskError).ok());
    const TaskAssignment next_for_a = *scheduler_.LeaseTask("a");
    EXPECT_NE(next_for_a.task.index, lease.task.index);
    const TaskAssignment next_for_b = *scheduler_.LeaseTask("b");
    EXPECT_EQ(next_for_b.task.index, lease.task.index);
}

TEST_F(SchedulerTest, LoneWorkerRetriesItsOwnFailure) {
    Submit(0, 16);  // one tile, two passes
    const TaskAssignment first = *scheduler_.LeaseTask("a");
    ASSERT_TRUE(scheduler_.Fail(first.lease_id, "a", "flaky", FailureKind::kTaskError).ok());
    EXPECT_EQ(scheduler_.LeaseTask("a")->task.index, 0);
}

TEST_F(SchedulerTest, ThirdFailureFailsTheJobWithTheReason) {
    const std::string id = Submit(0, 16);
    for (int attempt = 1; attempt <= 3; ++attempt) {
        std::optional<TaskAssignment> lease = scheduler_.LeaseTask("w");
        ASSERT_TRUE(lease.has_value());
        ASSERT_EQ(lease->task.index, 0);
        ASSERT_TRUE(
            scheduler_.Fail(lease->lease_id, "w", "mesh.obj: no such file", FailureKind::kTaskError)
                .ok());
        EXPECT_EQ(Job(id).state, attempt < 3 ? JobState::kRunning : JobState::kFailed);
    }
    EXPECT_NE(Job(id).error.find("mesh.obj: no such file"), std::string::npos) << Job(id).error;
    EXPECT_NE(Job(id).error.find("3 times"), std::string::npos) << Job(id).error;
    EXPECT_FALSE(scheduler_.LeaseTask("w").has_value());
}

TEST_F(SchedulerTest, LastErrorShowsWhileTheTaskIsRetried) {
    const std::string id = Submit(0, 16, 1);  // one task
    const TaskAssignment lease = *scheduler_.LeaseTask("w");
    ASSERT_TRUE(
        scheduler_.Fail(lease.lease_id, "w", "out of memory", FailureKind::kTaskError).ok());
    EXPECT_EQ(Job(id).state, JobState::kRunning);
    EXPECT_EQ(Job(id).last_error, "task 0: out of memory (worker w)");
    EXPECT_EQ(Job(id).error, "");
}

// With any number of workers, a task that fails on every attempt fails its job after
// max_attempts (3 by default) counted failures: once it failed on every live worker it is leased
// again.
class AlwaysFailingTaskTest : public SchedulerTest, public ::testing::WithParamInterface<int> {};

TEST_P(AlwaysFailingTaskTest, FailsTheJobAfterMaxFailuresNamingTheTaskAndTheLastReason) {
    const int workers = GetParam();
    const std::string id = Submit(0, 16, 1);  // one task
    int failures = 0;
    for (int round = 0; round < 10 && !IsFinal(Job(id).state); ++round) {
        for (int w = 0; w < workers; ++w) {  // every worker asks in turn, so all stay live
            const std::string worker = absl::StrCat("w", w);
            const std::optional<TaskAssignment> lease = scheduler_.LeaseTask(worker);
            if (!lease) continue;
            ++failures;
            const std::string reason = absl::StrCat("attempt ", failures, ": out of patches");
            ASSERT_TRUE(
                scheduler_.Fail(lease->lease_id, worker, reason, FailureKind::kTaskError).ok());
            if (Job(id).state == JobState::kRunning) {
                EXPECT_EQ(Job(id).last_error,
                          absl::StrCat("task 0: ", reason, " (worker ", worker, ")"));
            }
        }
    }
    EXPECT_EQ(Job(id).state, JobState::kFailed);
    EXPECT_EQ(failures, 3);
    EXPECT_NE(Job(id).error.find("task 0 failed 3 times"), std::string::npos) << Job(id).error;
    EXPECT_NE(Job(id).error.find("attempt 3: out of patches"), std::string::npos) << Job(id).error;
}

INSTANTIATE_TEST_SUITE_P(Workers, AlwaysFailingTaskTest, ::testing::Values(1, 2, 3));

// Job management (issue 30): the job's own max attempts, and the blocklist.
class JobManagementTest : public SchedulerTest {
  protected:
    // A 16x16 image in 8x8 tiles, one pass: 4 tasks.
    std::string SubmitWith(int max_attempts, int blocklist_after) {
        JobSpec spec;
        spec.name = "managed";
        spec.plan = {16, 16, 1, 8, 1};
        spec.max_attempts = max_attempts;
        spec.blocklist_after = blocklist_after;
        absl::StatusOr<std::string> id = scheduler_.Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return *id;
    }
    void FailNext(const std::string& worker, const std::string& reason) {
        const std::optional<TaskAssignment> lease = scheduler_.LeaseTask(worker);
        ASSERT_TRUE(lease.has_value()) << worker;
        ASSERT_TRUE(scheduler_.Fail(lease->lease_id, worker, reason, FailureKind::kTaskError).ok());
    }
};

TEST_F(JobManagementTest, MaxAttemptsOfTheJobFailIt) {
    const std::string id = SubmitWith(1, 3);
    FailNext("w", "out of memory");
    EXPECT_EQ(Job(id).state, JobState::kFailed);
    EXPECT_EQ(Job(id).error, "task 0 failed 1 time; last: out of memory (worker w)");
}

TEST_F(JobManagementTest, BlocklistedWorkerGetsNoMoreTasksOfTheJob) {
    const std::string id = SubmitWith(3, 2);
    scheduler_.LeaseTask("good");     // alive, holding task 0
    FailNext("bad", "no GPU");        // task 1
    FailNext("bad", "no GPU again");  // task 2: blocklisted
    EXPECT_FALSE(scheduler_.LeaseTask("bad").has_value());
    const JobRecord job = Job(id);
    EXPECT_EQ(job.state, JobState::kRunning);
    ASSERT_EQ(job.Blocklisted().size(), 1u);
    EXPECT_EQ(job.Blocklisted()[0].worker, "bad");
    EXPECT_EQ(job.Blocklisted()[0].failures, 2);
    EXPECT_EQ(job.Blocklisted()[0].last_error, "no GPU again (worker bad)");
    // Saved with the record, so it outlives a restart.
    ASSERT_EQ(store_.Get(id)->worker_failures.size(), 1u);
    EXPECT_EQ(store_.Get(id)->worker_failures[0].failures, 2);
    // The good worker renders the rest, the failed tasks included.
    for (int i = 0; i < 3; ++i) {
        const std::optional<TaskAssignment> lease = scheduler_.LeaseTask("good");
        ASSERT_TRUE(lease.has_value());
        ASSERT_TRUE(scheduler_.Complete(lease->lease_id, "good", Result(*lease)).ok());
    }
    EXPECT_EQ(Job(id).tasks_done, 3);
    EXPECT_FALSE(scheduler_.LeaseTask("bad").has_value());
}

// A task that failed on the good worker waits for another live worker only while one may
// take it: a blocklisted (or disabled, or tag-lacking) one never will, so the good worker takes it
// again rather than the job stalling.
TEST_F(JobManagementTest, ATaskFailedOnTheOnlyEligibleWorkerIsNotHeldForABlocklistedOne) {
    const std::string id = SubmitWith(3, 2);
    const std::optional<TaskAssignment> held = scheduler_.LeaseTask("good");  // task 0
    ASSERT_TRUE(held.has_value());
    FailNext("bad", "no GPU");  // task 1
    FailNext("bad", "no GPU");  // task 2: blocklisted, still live
    ASSERT_EQ(Job(id).Blocklisted().size(), 1u);
    ASSERT_TRUE(scheduler_.Fail(held->lease_id, "good", "flaky", FailureKind::kTaskError).ok());
    for (int i = 0; i < 4; ++i) {
        EXPECT_FALSE(scheduler_.LeaseTask("bad").has_value());  // the blocklisted one polls on
        const std::optional<TaskAssignment> lease = scheduler_.LeaseTask("good");
        ASSERT_TRUE(lease.has_value()) << "task " << i << " of 4 held back";
        ASSERT_TRUE(scheduler_.Complete(lease->lease_id, "good", Result(*lease)).ok());
    }
    EXPECT_EQ(Job(id).tasks_done, 4);
}

TEST_F(JobManagementTest, RequeueOfARunningJobResetsItsFailuresAndBlocklist) {
    const std::string id = SubmitWith(2, 2);
    scheduler_.LeaseTask("good");  // alive, holding task 0
    FailNext("bad", "no GPU");     // task 1
    FailNext("bad", "no GPU");     // task 2: blocklisted
    ASSERT_EQ(Job(id).Blocklisted().size(), 1u);
    absl::StatusOr<Scheduler::Requeued> requeued = scheduler_.RequeueJob(id);
    ASSERT_TRUE(requeued.ok()) << requeued.status();
    EXPECT_TRUE(requeued->record.Blocklisted().empty());
    EXPECT_EQ(requeued->record.last_error, "");
    EXPECT_TRUE(store_.Get(id)->worker_failures.empty());
    // The bad worker may take the tasks again, even those it failed, and each has its two
    // attempts again: one more failure of task 1 does not fail the job.
    const std::vector<TaskStatus> before = *scheduler_.Tasks(id);
    EXPECT_EQ(before[1].failures, 0);
    FailNext("bad", "no GPU");
    EXPECT_EQ(Job(id).state, JobState::kRunning);
}

TEST_F(JobManagementTest, RequeuedFailedJobIsQueuedAgainAndRenders) {
    const std::string id = SubmitWith(1, 3);
    FailNext("w", "out of memory");
    ASSERT_EQ(Job(id).state, JobState::kFailed);
    absl::StatusOr<Scheduler::Requeued> requeued = scheduler_.RequeueJob(id);
    ASSERT_TRUE(requeued.ok()) << requeued.status();
    EXPECT_EQ(Job(id).state, JobState::kQueued);
    EXPECT_EQ(Job(id).error, "");
    EXPECT_EQ(Job(id).finished, absl::InfinitePast());
    bool rendered = false;
    while (std::optional<TaskAssignment> lease = scheduler_.LeaseTask("w")) {
        absl::StatusOr<Scheduler::Completion> done =
            scheduler_.Complete(lease->lease_id, "w", Result(*lease));
        ASSERT_TRUE(done.ok()) << done.status();
        EXPECT_EQ(done->run, requeued->run);
        rendered = done->job_rendered;
    }
    EXPECT_TRUE(rendered);
    scheduler_.Finish({id, requeued->run}, std::string("/results/x.exr"));
    EXPECT_EQ(Job(id).state, JobState::kSucceeded);
}

TEST_F(JobManagementTest, RequeueOfAnEndedJobRespectsTheActiveJobLimit) {
    SchedulerOptions options = Options();
    options.max_active_jobs = 1;
    InMemoryJobStore store;
    Scheduler limited(options, store, [this] { return now_; });
    JobSpec spec;
    spec.name = "limited";
    spec.plan = {16, 16, 1, 8, 1};
    spec.max_attempts = 1;
    const absl::StatusOr<std::string> failed = limited.Submit(spec);
    ASSERT_TRUE(failed.ok()) << failed.status();
    const std::optional<TaskAssignment> lease = limited.LeaseTask("w");
    ASSERT_TRUE(lease.has_value());
    ASSERT_TRUE(limited.Fail(lease->lease_id, "w", "out of memory", FailureKind::kTaskError).ok());
    ASSERT_EQ(limited.Get(*failed)->state, JobState::kFailed);
    const absl::StatusOr<std::string> other = limited.Submit(spec);  // the one job allowed
    ASSERT_TRUE(other.ok()) << other.status();
    const absl::StatusOr<Scheduler::Requeued> refused = limited.RequeueJob(*failed);
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kResourceExhausted) << refused.status();
    EXPECT_NE(refused.status().message().find("--max-active-jobs"), std::string::npos);
    EXPECT_EQ(limited.Get(*failed)->state, JobState::kFailed);
    EXPECT_EQ(store.Get(*failed)->state, JobState::kFailed);
    ASSERT_TRUE(limited.Cancel(*other).ok());
    EXPECT_TRUE(limited.RequeueJob(*failed).ok());
    EXPECT_EQ(limited.Get(*failed)->state, JobState::kQueued);
}

TEST_F(JobManagementTest, APausedJobThatIsCancelledIsCancelledNotPaused) {
    const std::string id = SubmitWith(3, 3);
    ASSERT_TRUE(scheduler_.SetPaused(id, true).ok());
    absl::StatusOr<JobRecord> cancelled = scheduler_.Cancel(id);
    ASSERT_TRUE(cancelled.ok()) << cancelled.status();
    EXPECT_EQ(cancelled->state, JobState::kCancelled);
    EXPECT_FALSE(cancelled->paused);
    EXPECT_FALSE(Job(id).paused);
    EXPECT_FALSE(store_.Get(id)->paused);
}

TEST_F(JobManagementTest, PausedJobLeasesNothingNewButItsRunningTasksMerge) {
    const std::string id = SubmitWith(3, 3);
    const TaskAssignment running = *scheduler_.LeaseTask("w");
    absl::StatusOr<JobRecord> paused = scheduler_.SetPaused(id, true);
    ASSERT_TRUE(paused.ok()) << paused.status();
    EXPECT_TRUE(paused->paused);
    EXPECT_TRUE(store_.Get(id)->paused);  // durable
    EXPECT_FALSE(scheduler_.LeaseTask("w").has_value());
    ASSERT_TRUE(scheduler_.Complete(running.lease_id, "w", Result(running)).ok());
    EXPECT_EQ(Job(id).tasks_done, 1);
    EXPECT_EQ(Job(id).state, JobState::kRunning);
    ASSERT_TRUE(scheduler_.SetPaused(id, false).ok());
    EXPECT_TRUE(scheduler_.LeaseTask("w").has_value());
    ASSERT_TRUE(scheduler_.Cancel(id).ok());
    EXPECT_EQ(scheduler_.SetPaused(id, true).status().code(),
              absl::StatusCode::kFailedPrecondition);

    // Near its end (nothing queued, one slow task running), a paused job gives an idle worker
    // no second lease of its straggler either.
    const std::string two = Submit(0, 16);  // two tasks
    const TaskAssignment slow = *scheduler_.LeaseTask("slow");
    const TaskAssignment fast = *scheduler_.LeaseTask("fast");
    now_ += absl::Milliseconds(500);
    ASSERT_TRUE(scheduler_.Complete(fast.lease_id, "fast", Result(fast)).ok());
    now_ += absl::Seconds(1);  // slow now: a straggler (StragglersTaskIsLeasedAgain...)
    ASSERT_TRUE(scheduler_.SetPaused(two, true).ok());
    EXPECT_FALSE(scheduler_.LeaseTask("fast").has_value()) << "a second lease of a paused job";
    ASSERT_TRUE(scheduler_.SetPaused(two, false).ok());
    EXPECT_TRUE(scheduler_.LeaseTask("fast").has_value()) << "the straggler, once resumed";
    EXPECT_EQ(scheduler_.SetPaused("job-none", true).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(JobManagementTest, JobFailsWhenEveryLiveWorkerIsBlocklisted) {
    const std::string id = SubmitWith(5, 2);
    FailNext("bad", "no GPU");
    EXPECT_EQ(Job(id).state, JobState::kRunning);
    FailNext("bad", "no GPU");
    EXPECT_EQ(Job(id).state, JobState::kFailed);
    EXPECT_EQ(Job(id).error,
              "every live worker is blocklisted from the job: bad (2 failures, last: no GPU "
              "(worker bad))");
}

TEST_F(SchedulerTest, MadeUpWorkerIdsAreForgottenAfterALease) {
    for (int i = 0; i < 100'000; ++i) {
        EXPECT_FALSE(scheduler_.LeaseTask(absl::StrCat("made-up-", i)).has_value());
        EXPECT_FALSE(scheduler_.Heartbeat("job-x/0/forged-1", absl::StrCat("forged-", i)));
    }
    EXPECT_EQ(scheduler_.workers_tracked(), 100'000u);  // the forged heartbeats are not kept
    Submit(0);
    const TaskAssignment lease = *scheduler_.LeaseTask("real");
    now_ += absl::Seconds(9);
    ASSERT_TRUE(scheduler_.Heartbeat(lease.lease_id, "real"));
    now_ += absl::Seconds(2);                 // the made-up ones are silent for a lease now
    EXPECT_EQ(scheduler_.ExpireLeases(), 0);  // the timeout checker's tick
    EXPECT_EQ(scheduler_.workers_tracked(), 1u);
}

TEST_F(SchedulerTest, ExpiriesCountAsFailuresButShutdownsDoNot) {
    const std::string id = Submit(0, 16);
    for (int i = 0; i < 10; ++i) {
        const TaskAssignment lease = *scheduler_.LeaseTask("w");
        ASSERT_TRUE(
            scheduler_
                .Fail(lease.lease_id, "w", "worker shutting down", FailureKind::kWorkerShutdown)
                .ok());
    }
    EXPECT_EQ(Job(id).state, JobState::kRunning);
    // Leases their worker took (it heartbeated) and then lost.
    for (int i = 0; i < 3; ++i) {
        const std::optional<TaskAssignment> lease = scheduler_.LeaseTask("w");
        ASSERT_TRUE(lease.has_value());
        ASSERT_TRUE(scheduler_.Heartbeat(lease->lease_id, "w"));
        now_ += absl::Seconds(11);
        scheduler_.ExpireLeases();
    }
    EXPECT_EQ(Job(id).state, JobState::kFailed);
    EXPECT_NE(Job(id).error.find("lease expired"), std::string::npos) << Job(id).error;
}

// One worker token leasing under ever new ids and never answering failed 197 of 200 jobs in
// 10 s: a lease that expires before any heartbeat is not the task's failure.
TEST_F(SchedulerTest, LeasesAbandonedUnderFreshIdsFailNoJob) {
    const std::string id = Submit(0, 16, 1);  // one task
    int abandoned = 0;                        // the token's quarantine refuses some of the 20
    for (int i = 0; i < 20; ++i) {
        abandoned += scheduler_.LeaseTask("evil/" + std::to_string(i)).has_value();
        now_ += absl::Seconds(11);
        scheduler_.ExpireLeases();
    }
    EXPECT_GT(abandoned, 3);
    EXPECT_EQ(Job(id).state, JobState::kRunning);
    const std::optional<TaskAssignment> honest = scheduler_.LeaseTask("node/w");
    ASSERT_TRUE(honest.has_value());
    ASSERT_TRUE(scheduler_.Complete(honest->lease_id, "node/w", Result(*honest)).ok());
    EXPECT_EQ(Job(id).tasks_done, 1);
    EXPECT_NE(Job(id).state, JobState::kFailed);
}

// A token whose workers' leases keep expiring unheard, under a fresh id each time, is
// quarantined as a whole (as a worker, each id had one strike only); other tokens still lease,
// and a lease its worker answers clears the token's strikes.
TEST_F(SchedulerTest, ATokenLeasingUnderFreshIdsAndNeverAnsweringIsQuarantined) {
    Submit(0, 16);
    std::string expired;
    for (int i = 0; i < WorkerRegistry::kAbandonedInARow; ++i) {
        const std::optional<TaskAssignment> lease =
            scheduler_.LeaseTask("evil/" + std::to_string(i));
        ASSERT_TRUE(lease.has_value()) << i;
        expired = lease->lease_id;
        now_ += absl::Seconds(11);
        scheduler_.ExpireLeases();
    }
    EXPECT_FALSE(scheduler_.LeaseTask("evil/fresh").has_value()) << "the token is quarantined";
    // A heartbeat on a lease that expired is refused, and lifts no quarantine.
    EXPECT_FALSE(scheduler_.Heartbeat(expired, "evil/2"));
    EXPECT_FALSE(scheduler_.LeaseTask("evil/fresh").has_value()) << "still quarantined";
    const std::optional<TaskAssignment> other = scheduler_.LeaseTask("node/w");
    ASSERT_TRUE(other.has_value());
    ASSERT_TRUE(
        scheduler_.Fail(other->lease_id, "node/w", "stop", FailureKind::kWorkerShutdown).ok());
    now_ += absl::Seconds(10 * 10);  // quarantine_leases leases
    const std::optional<TaskAssignment> again = scheduler_.LeaseTask("evil/later");
    ASSERT_TRUE(again.has_value()) << "quarantine over";
    ASSERT_TRUE(scheduler_.Heartbeat(again->lease_id, "evil/later"));
    // Two strikes, then an answered lease: the count starts again.
    for (int i = 0; i < WorkerRegistry::kAbandonedInARow - 1; ++i) {
        now_ += absl::Seconds(11);
        scheduler_.ExpireLeases();
        ASSERT_TRUE(scheduler_.LeaseTask("evil/again" + std::to_string(i)).has_value()) << i;
    }
    EXPECT_TRUE(scheduler_.LeaseTask("evil/one-more").has_value());
}

// A worker whose leases keep expiring unheard gets none for a while; the others still do.
TEST_F(SchedulerTest, AWorkerThatKeepsAbandoningLeasesIsQuarantined) {
    Submit(0, 16);
    for (int i = 0; i < WorkerRegistry::kAbandonedInARow; ++i) {
        ASSERT_TRUE(scheduler_.LeaseTask("flaky").has_value()) << i;
        now_ += absl::Seconds(11);
        scheduler_.ExpireLeases();
    }
    EXPECT_FALSE(scheduler_.LeaseTask("flaky").has_value()) << "quarantined";
    const std::optional<TaskAssignment> other = scheduler_.LeaseTask("steady");
    ASSERT_TRUE(other.has_value());
    ASSERT_TRUE(
        scheduler_.Fail(other->lease_id, "steady", "stop", FailureKind::kWorkerShutdown).ok());
    now_ += absl::Seconds(10 * 10);  // quarantine_leases leases
    EXPECT_TRUE(scheduler_.LeaseTask("flaky").has_value()) << "quarantine over";
}

// However many worker ids one token claims, its workers hold at most max_leases_per_token tasks.
TEST(SchedulerLeaseCap, OneTokensWorkersHoldAtMostTheCap) {
    SchedulerOptions options;
    options.max_leases_per_token = 2;
    InMemoryJobStore store;
    Scheduler scheduler(options, store);
    JobSpec spec;
    spec.name = "capped";
    spec.plan = {16, 16, 4, 8, 2};  // 8 tasks
    ASSERT_TRUE(scheduler.Submit(spec).ok());
    EXPECT_TRUE(scheduler.LeaseTask("evil/a").has_value());
    EXPECT_TRUE(scheduler.LeaseTask("evil/b").has_value());
    EXPECT_FALSE(scheduler.LeaseTask("evil/c").has_value());
    EXPECT_TRUE(scheduler.LeaseTask("node/a").has_value()) << "another token's worker";
}

TEST_F(SchedulerTest, LateResultOfAnExpiredLeaseIsMergedOnce) {
    const std::string id = Submit(0, 16);
    const TaskAssignment slow = *scheduler_.LeaseTask("slow");
    now_ += absl::Seconds(11);
    scheduler_.ExpireLeases();
    const TaskAssignment retry = *scheduler_.LeaseTask("fast");
    ASSERT_EQ(retry.task.index, slow.task.index);
    ASSERT_TRUE(scheduler_.Complete(slow.lease_id, "slow", Result(slow)).ok());
    EXPECT_FALSE(scheduler_.Heartbeat(retry.lease_id, "fast"));  // nothing left to do for it
    absl::StatusOr<Scheduler::Completion> again =
        scheduler_.Complete(retry.lease_id, "fast", Result(retry));
    ASSERT_TRUE(again.ok());
    EXPECT_FALSE(again->job_rendered);
    EXPECT_EQ(Job(id).tasks_done, 1);
    EXPECT_EQ(Job(id).tasks_running, 0);
}

TEST_F(SchedulerTest, WrongResultIsRefused) {
    Submit(0);
    const TaskAssignment lease = *scheduler_.LeaseTask("w");
    TileSums wrong(PixelRect{0, 0, 3, 3});
    EXPECT_EQ(scheduler_.Complete(lease.lease_id, "w", wrong).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(scheduler_.Complete("job-nope/0/1", "w", wrong).status().code(),
              absl::StatusCode::kFailedPrecondition);
}

TEST_F(SchedulerTest, ResultForALeaseTheWorkerDoesNotHoldIsRefused) {
    const std::string id = Submit(0);
    const TaskAssignment lease = *scheduler_.LeaseTask("a");
    EXPECT_EQ(scheduler_.Complete(lease.lease_id, "b", Result(lease)).status().code(),
              absl::StatusCode::kFailedPrecondition);
    EXPECT_FALSE(scheduler_.Heartbeat(lease.lease_id, "b"));
    ASSERT_TRUE(scheduler_.Fail(lease.lease_id, "b", "?", FailureKind::kTaskError).ok());
    std::string forged = lease.lease_id;
    // An id never handed out: one hex digit changed (ids are random, so it may already be 7).
    forged.back() = forged.back() == '7' ? '8' : '7';
    EXPECT_EQ(scheduler_.Complete(forged, "a", Result(lease)).status().code(),
              absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(Job(id).tasks_done, 0);
    EXPECT_EQ(Job(id).retries, 0);
    EXPECT_TRUE(scheduler_.Heartbeat(lease.lease_id, "a"));
    EXPECT_TRUE(scheduler_.Complete(lease.lease_id, "a", Result(lease)).ok());
    EXPECT_EQ(Job(id).tasks_done, 1);
}

TEST_F(SchedulerTest, WrongResultQueuesTheTaskAgainAtOnce) {
    const std::string id = Submit(0);
    scheduler_.LeaseTask("b");  // b is alive
    const TaskAssignment lease = *scheduler_.LeaseTask("a");
    TileSums wrong(lease.task.rect);  // the right rectangle without its samples
    EXPECT_EQ(scheduler_.Complete(lease.lease_id, "a", wrong).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(Job(id).retries, 1);
    EXPECT_EQ(Job(id).tasks_done, 0);
    EXPECT_FALSE(scheduler_.Heartbeat(lease.lease_id, "a"));
    EXPECT_EQ(scheduler_.LeaseTask("b")->task.index, lease.task.index);
}

TEST_F(SchedulerTest, StragglersTaskIsLeasedAgainNearTheEndAndTheFirstResultWins) {
    const std::string id = Submit(0, 16);  // two tasks
    const TaskAssignment slow = *scheduler_.LeaseTask("slow");
    const TaskAssignment fast = *scheduler_.LeaseTask("fast");
    now_ += absl::Milliseconds(500);
    ASSERT_TRUE(scheduler_.Complete(fast.lease_id, "fast", Result(fast)).ok());
    EXPECT_FALSE(scheduler_.LeaseTask("fast"));  // not slow yet
    now_ += absl::Seconds(1);
    EXPECT_FALSE(scheduler_.LeaseTask("slow")) << "its own task is not leased to it again";
    const std::optional<TaskAssignment> copy = scheduler_.LeaseTask("fast");
    ASSERT_TRUE(copy);
    EXPECT_EQ(copy->task.index, slow.task.index);
    EXPECT_FALSE(scheduler_.LeaseTask("idle")) << "one speculative copy at a time";
    EXPECT_EQ(Job(id).tasks_running, 1);
    absl::StatusOr<Scheduler::Completion> done =
        scheduler_.Complete(copy->lease_id, "fast", Result(*copy));
    ASSERT_TRUE(done.ok()) << done.status();
    EXPECT_TRUE(done->job_rendered);
    EXPECT_FALSE(scheduler_.Heartbeat(slow.lease_id, "slow"));  // told to stop
    EXPECT_EQ(Job(id).tasks_leased, 3);
    EXPECT_EQ(Job(id).tasks_running, 0);
}

// A task's original lease and its speculative copy expiring in the same tick of the timeout
// checker (both workers gone at once, or the checker late): each counts as a failure, the task
// is queued again once, and the job goes on (it used to move the task from queued to queued, a
// broken invariant that aborted the coordinator).
TEST_F(SchedulerTest, OriginalAndSpeculativeCopyExpiringInOneTickQueueTheTaskOnce) {
    const std::string id = Submit(0, 16);  // two tasks
    const TaskAssignment slow = *scheduler_.LeaseTask("slow");
    const TaskAssignment fast = *scheduler_.LeaseTask("fast");
    ASSERT_TRUE(scheduler_.Complete(fast.lease_id, "fast", Result(fast)).ok());
    now_ += absl::Seconds(2);
    const TaskAssignment copy = *scheduler_.LeaseTask("fast");
    ASSERT_EQ(copy.task.index, slow.task.index);
    now_ += absl::Seconds(30);  // past both leases
    EXPECT_EQ(scheduler_.ExpireLeases(), 2);
    EXPECT_EQ(Job(id).state, JobState::kRunning);
    EXPECT_EQ(Job(id).tasks_running, 0);
    EXPECT_EQ(Job(id).retries, 1);
    const std::optional<TaskAssignment> again = scheduler_.LeaseTask("third");
    ASSERT_TRUE(again);
    EXPECT_EQ(again->task.index, slow.task.index);
    ASSERT_TRUE(scheduler_.Complete(again->lease_id, "third", Result(*again)).ok());
    EXPECT_EQ(Job(id).tasks_done, 2);
}

TEST_F(SchedulerTest, FailedSpeculativeCopyLeavesTheOriginalRunning) {
    const std::string id = Submit(0, 16);
    const TaskAssignment slow = *scheduler_.LeaseTask("slow");
    const TaskAssignment fast = *scheduler_.LeaseTask("fast");
    ASSERT_TRUE(scheduler_.Complete(fast.lease_id, "fast", Result(fast)).ok());
    now_ += absl::Seconds(2);
    const TaskAssignment copy = *scheduler_.LeaseTask("fast");
    ASSERT_TRUE(scheduler_.Fail(copy.lease_id, "fast", "oops", FailureKind::kTaskError).ok());
    EXPECT_TRUE(scheduler_.Heartbeat(slow.lease_id, "slow"));
    EXPECT_EQ(Job(id).tasks_running, 1);
    EXPECT_FALSE(scheduler_.LeaseTask("fast")) << "it failed there";
    ASSERT_TRUE(scheduler_.Complete(slow.lease_id, "slow", Result(slow)).ok());
    EXPECT_EQ(Job(id).tasks_done, 2);
}

TEST_F(SchedulerTest, CancelStopsLeasesAndIsFinal) {
    const std::string id = Submit(0);
    const TaskAssignment lease = *scheduler_.LeaseTask("w");
    absl::StatusOr<JobRecord> cancelled = scheduler_.Cancel(id);
    ASSERT_TRUE(cancelled.ok());
    EXPECT_EQ(cancelled->state, JobState::kCancelled);
    EXPECT_EQ(cancelled->tasks_running, 0);
    EXPECT_FALSE(scheduler_.Heartbeat(lease.lease_id, "w"));
    EXPECT_FALSE(scheduler_.LeaseTask("w").has_value());
    EXPECT_EQ(scheduler_.Complete(lease.lease_id, "w", Result(lease)).status().code(),
              absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(scheduler_.Cancel(id).status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(scheduler_.Cancel("job-unknown").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(SchedulerTest, WaitForChangeWakesOnAnyChange) {
    const uint64_t v = scheduler_.WaitForChange(0, absl::InfinitePast());
    EXPECT_EQ(scheduler_.WaitForChange(v, absl::Now() + absl::Milliseconds(10)), v);
    Submit(0);
    EXPECT_GT(scheduler_.WaitForChange(v, absl::Now() + absl::Seconds(10)), v);
}

TEST_F(SchedulerTest, IdleWorkerWaitsForWorkAndGetsItAtOnce) {
    EXPECT_FALSE(scheduler_.LeaseTask("w", absl::Now() + absl::Milliseconds(20)).has_value());
    // The delay only lets the worker start waiting first. The wait outlasts any test: only the
    // submission's wake-up ends it in time, whatever the machine's load.
    std::thread submitter([&] {
        absl::SleepFor(absl::Milliseconds(50));
        Submit(0);
    });
    const std::optional<TaskAssignment> lease =
        scheduler_.LeaseTask("w", absl::Now() + absl::Hours(1));
    submitter.join();
    EXPECT_TRUE(lease.has_value());
}

TEST_F(SchedulerTest, ShutdownEndsTheWait) {
    std::thread stopper([this] {
        absl::SleepFor(absl::Milliseconds(50));
        scheduler_.Shutdown();
    });
    // A wait that outlasts any test: only Shutdown ends it in time.
    EXPECT_FALSE(scheduler_.LeaseTask("w", absl::Now() + absl::Hours(1)).has_value());
    stopper.join();
}

TEST_F(SchedulerTest, ListIsNewestFirst) {
    const std::string a = Submit(0), b = Submit(0);
    const std::vector<JobRecord> jobs = *scheduler_.List();
    ASSERT_EQ(jobs.size(), 2u);
    EXPECT_EQ(jobs[0].id, b);
    EXPECT_EQ(jobs[1].id, a);
}

// An adaptive job on a 16x16 image in 8x8 tiles, first pass 4 spp. Tile (8, 8) is noisy (the
// A half reads 0.4, the B half 0.6: a relative error of 0.2 whatever the count), the others flat.
std::string SubmitAdaptive(Scheduler& scheduler, const AdaptiveSettings& adaptive) {
    JobSpec spec;
    spec.name = "adaptive";
    spec.plan = {16, 16, 4, 8, 1};
    spec.adaptive = adaptive;
    absl::StatusOr<std::string> id = scheduler.Submit(spec);
    EXPECT_TRUE(id.ok()) << id.status();
    return *id;
}

TileSums HalvesResult(const TaskAssignment& lease) {
    TileSums sums(lease.task.rect);
    const bool noisy = lease.task.rect.x0 == 8 && lease.task.rect.y0 == 8;
    for (PixelSums& p : sums.pixels) {
        for (uint64_t s = lease.task.sample_begin; s < lease.task.sample_end; ++s) {
            p.Add(s, Rgb(noisy ? (s % 2 ? 0.6f : 0.4f) : 0.5f));
        }
    }
    return sums;
}

TEST_F(SchedulerTest, AdaptiveJobQueuesPassesOnlyForTheTileAboveTheTarget) {
    const std::string id = SubmitAdaptive(scheduler_, {.target_error = 0.1, .max_spp = 64});
    EXPECT_EQ(Job(id).tasks_total, 4);
    std::vector<uint64_t> pass_ends;
    while (std::optional<TaskAssignment> lease = scheduler_.LeaseTask("w")) {
        if (lease->task.index >= 4) {
            EXPECT_EQ(lease->task.rect.x0, 8);
            EXPECT_EQ(lease->task.rect.y0, 8);
            pass_ends.push_back(lease->task.sample_end);
        }
        ASSERT_TRUE(scheduler_.Complete(lease->lease_id, "w", HalvesResult(*lease)).ok());
    }
    // Error 0.2 against 0.1 asks for 4x the samples plus 10 %, each pass; never below target.
    EXPECT_EQ(pass_ends, (std::vector<uint64_t>{18, 64}));
    EXPECT_EQ(Job(id).tasks_total, 6);
    EXPECT_EQ(Job(id).tasks_done, 6);
    auto snapshot = scheduler_.Snapshot(id);
    ASSERT_TRUE(snapshot.ok());
    ASSERT_TRUE(snapshot->adaptive.has_value());
    EXPECT_EQ(snapshot->adaptive->max_spp, 64u);
    EXPECT_EQ(snapshot->adaptive->min_spp, 4u);
    EXPECT_EQ(snapshot->adaptive->tiles_above_target, 1);  // stopped by max_spp
    EXPECT_EQ((*snapshot->image.FindChannel("spp"))[15 * 16 + 15], 64.0f);
}

// The jobs of runs, as EnforceTimeLimits and Recover report them.
std::vector<std::string> JobsOf(const std::vector<Scheduler::JobRun>& runs) {
    std::vector<std::string> ids;
    for (const Scheduler::JobRun& run : runs) ids.push_back(run.job_id);
    return ids;
}

// An adaptive job's four first passes (SubmitAdaptive) leased and merged with HalvesResult.
void CompleteFirstPasses(Scheduler& scheduler) {
    for (int i = 0; i < 4; ++i) {
        const std::optional<TaskAssignment> lease = scheduler.LeaseTask("w");
        ASSERT_TRUE(lease.has_value());
        ASSERT_TRUE(scheduler.Complete(lease->lease_id, "w", HalvesResult(*lease)).ok());
    }
}

TEST_F(SchedulerTest, TimeLimitDropsPassesStopsTheirLeasesAndEndsTheJob) {
    const std::string id = SubmitAdaptive(scheduler_, {.time_limit = 5, .max_spp = 1 << 10});
    CompleteFirstPasses(scheduler_);  // each asking for a second
    const std::optional<TaskAssignment> running = scheduler_.LeaseTask("w");
    ASSERT_TRUE(running.has_value());
    EXPECT_EQ(running->task.sample_begin, 4u);
    EXPECT_EQ(running->task.sample_end, 8u);
    EXPECT_TRUE(scheduler_.EnforceTimeLimits().empty());
    now_ += absl::Seconds(5);
    EXPECT_EQ(JobsOf(scheduler_.EnforceTimeLimits()), std::vector<std::string>{id});
    EXPECT_TRUE(scheduler_.EnforceTimeLimits().empty());         // reported once
    EXPECT_FALSE(scheduler_.Heartbeat(running->lease_id, "w"));  // the worker stops
    EXPECT_FALSE(scheduler_.LeaseTask("w").has_value());
    // Its late result changes nothing.
    absl::StatusOr<Scheduler::Completion> late =
        scheduler_.Complete(running->lease_id, "w", HalvesResult(*running));
    ASSERT_TRUE(late.ok());
    EXPECT_FALSE(late->job_rendered);
    EXPECT_EQ(Job(id).tasks_done, 4);
    EXPECT_EQ(Job(id).tasks_total, 4);
    auto snapshot = scheduler_.Snapshot(id);
    ASSERT_TRUE(snapshot.ok());
    EXPECT_TRUE(snapshot->adaptive->timed_out);
    EXPECT_EQ(snapshot->adaptive->max_spp, 4u);
}

// A paused job's time limit does not run out while it is paused: the clock stops and goes on
// from where it was on resume.
TEST_F(SchedulerTest, TimeLimitClockStopsWhileTheJobIsPaused) {
    const std::string id = SubmitAdaptive(scheduler_, {.time_limit = 5, .max_spp = 1 << 10});
    CompleteFirstPasses(scheduler_);                     // each asking for a second
    ASSERT_TRUE(scheduler_.LeaseTask("w").has_value());  // a second pass
    now_ += absl::Seconds(2);
    ASSERT_TRUE(scheduler_.SetPaused(id, true).ok());
    now_ += absl::Seconds(10);
    EXPECT_TRUE(scheduler_.EnforceTimeLimits().empty()) << "ran out while paused";
    ASSERT_TRUE(scheduler_.SetPaused(id, false).ok());
    now_ += absl::Seconds(2);  // 4 s of the 5 run
    EXPECT_TRUE(scheduler_.EnforceTimeLimits().empty());
    now_ += absl::Seconds(1);
    EXPECT_EQ(JobsOf(scheduler_.EnforceTimeLimits()), std::vector<std::string>{id});
}

// The time paused is in the job's record: a coordinator restarted during a pause keeps the
// clock stopped for it. (This test store keeps no task results: the restarted scheduler renders
// the first passes again.)
TEST_F(SchedulerTest, TimeLimitClockStaysStoppedForAPauseAcrossARestart) {
    const std::string id = SubmitAdaptive(scheduler_, {.time_limit = 5, .max_spp = 1 << 10});
    CompleteFirstPasses(scheduler_);
    now_ += absl::Seconds(2);
    ASSERT_TRUE(scheduler_.SetPaused(id, true).ok());
    now_ += absl::Seconds(10);
    Scheduler restarted(Options(), store_, [this] { return now_; });
    ASSERT_TRUE(restarted.Recover().ok());
    now_ += absl::Seconds(10);
    EXPECT_TRUE(restarted.EnforceTimeLimits().empty()) << "ran out while paused";
    ASSERT_TRUE(restarted.SetPaused(id, false).ok());
    CompleteFirstPasses(restarted);
    ASSERT_TRUE(restarted.LeaseTask("w").has_value());  // a second pass
    now_ += absl::Seconds(2);                           // 4 s of the 5 run
    EXPECT_TRUE(restarted.EnforceTimeLimits().empty());
    now_ += absl::Seconds(1);
    EXPECT_EQ(JobsOf(restarted.EnforceTimeLimits()), std::vector<std::string>{id});
}

// A job its last result completed is reported by Complete, and not again by the time limit.
TEST_F(SchedulerTest, TimeLimitDoesNotReportAJobItsLastResultCompleted) {
    const std::string id = SubmitAdaptive(scheduler_, {.target_error = 0.5, .time_limit = 5});
    bool rendered = false;
    while (std::optional<TaskAssignment> lease = scheduler_.LeaseTask("w")) {
        absl::StatusOr<Scheduler::Completion> done =
            scheduler_.Complete(lease->lease_id, "w", HalvesResult(*lease));
        ASSERT_TRUE(done.ok());
        rendered |= done->job_rendered;
    }
    EXPECT_TRUE(rendered);
    EXPECT_EQ(Job(id).tasks_done, 4);
    now_ += absl::Seconds(6);
    EXPECT_TRUE(scheduler_.EnforceTimeLimits().empty());
}

// A store that holds back durability and request lookups while told to, so a test can ask the
// scheduler questions while another thread waits on the store.
class HeldStore : public InMemoryJobStore {
  public:
    absl::Status WaitDurable(uint64_t ticket) override {
        Block();
        return InMemoryJobStore::WaitDurable(ticket);
    }
    absl::StatusOr<std::optional<std::string>> FindRequest(
        const std::string& request_id) const override {
        Block();
        return InMemoryJobStore::FindRequest(request_id);
    }
    void Hold() {
        std::lock_guard<std::mutex> lock(mutex_);
        held_ = true;
    }
    void Release() {
        std::lock_guard<std::mutex> lock(mutex_);
        held_ = false;
        cv_.notify_all();
    }
    void AwaitBlocked() {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return blocked_ > 0; });
    }

  private:
    void Block() const {
        std::unique_lock<std::mutex> lock(mutex_);
        ++blocked_;
        cv_.notify_all();
        cv_.wait(lock, [this] { return !held_; });
        --blocked_;
    }
    mutable std::mutex mutex_;
    mutable std::condition_variable cv_;
    bool held_ = false;
    mutable int blocked_ = 0;
};

// Runs `question` on another thread while `store` holds back another thread's call; true when it
// was answered meanwhile, that is without waiting for the store.
template <typename F>
bool AnsweredWhileTheStoreWaits(HeldStore& store, F question) {
    std::future<void> answer = std::async(std::launch::async, question);
    const bool answered = answer.wait_for(std::chrono::seconds(30)) == std::future_status::ready;
    store.Release();
    answer.get();
    return answered;
}

JobSpec SmallSpec(const std::string& request_id) {
    JobSpec spec;
    spec.name = "held";
    spec.plan = {16, 16, 4, 8, 1};
    spec.request_id = request_id;
    return spec;
}

TEST(SchedulerLockTest, EndingAJobWaitsForTheStoreWithoutTheLock) {
    HeldStore store;
    Scheduler scheduler({}, store);
    const std::string id = *scheduler.Submit(SmallSpec(""));
    store.Hold();
    std::thread cancel([&] {
        absl::StatusOr<JobRecord> cancelled = scheduler.Cancel(id);
        EXPECT_TRUE(cancelled.ok()) << cancelled.status();
    });
    store.AwaitBlocked();
    EXPECT_TRUE(AnsweredWhileTheStoreWaits(store, [&] {
        EXPECT_EQ(scheduler.Get(id)->state, JobState::kCancelled);
        EXPECT_FALSE(scheduler.LeaseTask("w").has_value());
    }));
    cancel.join();
    EXPECT_EQ(store.Get(id)->state, JobState::kCancelled);
}

// A job's tasks are handed on (the farm records them for `lightfarm tasks`) before its end
// settles: a client told of the end lists them at once. While the callback runs, a wait for
// the end goes on.
TEST(SchedulerLockTest, TasksAreHandedOnBeforeTheEndSettles) {
    using EndWait = Scheduler::EndWait;
    InMemoryJobStore store;
    Scheduler scheduler({}, store);
    std::promise<void> entered, release;
    std::shared_future<void> released = release.get_future().share();
    scheduler.OnTasksEnded([&](const JobRecord&, std::vector<TaskStatus> tasks) {
        EXPECT_FALSE(tasks.empty());
        entered.set_value();
        released.wait();
    });
    const std::string id = *scheduler.Submit(SmallSpec(""));
    std::thread cancel([&] { EXPECT_TRUE(scheduler.Cancel(id).ok()); });
    entered.get_future().wait();
    EXPECT_EQ(scheduler.WaitForEnd(id, absl::Now() + absl::Milliseconds(50)), EndWait::kRunning);
    release.set_value();
    EXPECT_EQ(scheduler.WaitForEnd(id, absl::Now() + absl::Hours(1)), EndWait::kEnded);
    cancel.join();
}

// A result is answered once its record is durable; the one that renders the job is not waited
// for by Complete (the farm writes the image meanwhile) but by AwaitRecorded.
TEST(SchedulerLockTest, TheLastResultIsRecordedWhileTheImageIsWritten) {
    HeldStore store;
    Scheduler scheduler({}, store);
    const std::string id = *scheduler.Submit(SmallSpec(""));
    std::vector<TaskAssignment> leases;
    while (std::optional<TaskAssignment> l = scheduler.LeaseTask("w")) leases.push_back(*l);
    ASSERT_GE(leases.size(), 2u);
    const auto complete = [&](const TaskAssignment& lease) {
        return scheduler.Complete(lease.lease_id, "w", testing::UniformResult(lease, Rgb(0.5f)));
    };
    store.Hold();
    std::future<absl::StatusOr<Scheduler::Completion>> first =
        std::async(std::launch::async, [&] { return complete(leases[0]); });
    store.AwaitBlocked();  // an earlier result waits for its record
    store.Release();
    ASSERT_TRUE(first.get().ok());
    for (size_t i = 1; i + 1 < leases.size(); ++i) ASSERT_TRUE(complete(leases[i]).ok());

    store.Hold();
    std::future<absl::StatusOr<Scheduler::Completion>> answered =
        std::async(std::launch::async, [&] { return complete(leases.back()); });
    const bool returned = answered.wait_for(std::chrono::seconds(30)) == std::future_status::ready;
    if (!returned) store.Release();  // a Complete that waited again: fail, not hang
    ASSERT_TRUE(returned) << "Complete waited for the last result's record";
    const absl::StatusOr<Scheduler::Completion> last = answered.get();
    ASSERT_TRUE(last.ok()) << last.status();
    EXPECT_TRUE(last->job_rendered);
    ASSERT_TRUE(last->unrecorded.has_value());
    EXPECT_EQ(last->unrecorded->task, leases.back().task.index);
    EXPECT_TRUE(scheduler.Snapshot(id).ok());  // the image can be written meanwhile
    std::future<absl::Status> recorded =
        std::async(std::launch::async, [&] { return scheduler.AwaitRecorded(*last); });
    store.AwaitBlocked();
    EXPECT_EQ(recorded.wait_for(std::chrono::milliseconds(50)), std::future_status::timeout);
    store.Release();
    EXPECT_TRUE(recorded.get().ok());
    scheduler.Finish({id, last->run}, std::string("/results/x.exr"));
    EXPECT_EQ(store.Get(id)->state, JobState::kSucceeded);
}

// What WatchJob reads and waits for before it sends a job's end: the end settled, its record
// durable. Until then GetSettled reads nothing, and a wait that began while the job ran (its
// deadline beyond any test) goes on: at the end in memory, a requeue would still be refused.
TEST(SchedulerLockTest, GetSettledAndWaitForEndSeeTheEndOnceItIsDurable) {
    using EndWait = Scheduler::EndWait;
    HeldStore store;
    Scheduler scheduler({}, store);
    const std::string id = *scheduler.Submit(SmallSpec(""));
    EXPECT_EQ(scheduler.WaitForEnd(id, absl::InfinitePast()), EndWait::kRunning);
    EXPECT_EQ((*scheduler.GetSettled(id))->state, JobState::kQueued);
    std::future<EndWait> waited = std::async(std::launch::async, [&] {
        const EndWait end = scheduler.WaitForEnd(id, absl::Now() + absl::Hours(1));
        // Asked before the test releases anything more: the job is requeued at once.
        EXPECT_TRUE(scheduler.RequeueJob(id).ok());
        return end;
    });
    store.Hold();
    std::thread cancel([&] { EXPECT_TRUE(scheduler.Cancel(id).ok()); });
    store.AwaitBlocked();
    EXPECT_EQ(scheduler.Get(id)->state, JobState::kCancelled);
    EXPECT_FALSE(scheduler.GetSettled(id)->has_value());
    EXPECT_EQ(scheduler.WaitForEnd(id, absl::InfinitePast()), EndWait::kRunning);
    EXPECT_TRUE(absl::IsUnavailable(scheduler.RequeueJob(id).status()));
    EXPECT_EQ(waited.wait_for(std::chrono::seconds(0)), std::future_status::timeout);
    store.Release();
    cancel.join();
    EXPECT_EQ(waited.get(), EndWait::kEnded);
    EXPECT_EQ((*scheduler.GetSettled(id))->state, JobState::kQueued);
    EXPECT_EQ(scheduler.WaitForEnd("job-unknown", absl::InfinitePast()), EndWait::kEnded);
    EXPECT_TRUE(absl::IsNotFound(scheduler.GetSettled("job-unknown").status()));
}

// Shutdown ends a wait for a job that has not ended; one that ended is still reported so.
TEST(SchedulerLockTest, ShutdownEndsAWaitForAJobsEnd) {
    using EndWait = Scheduler::EndWait;
    InMemoryJobStore store;
    Scheduler scheduler({}, store);
    const std::string running = *scheduler.Submit(SmallSpec("")),
                      ended = *scheduler.Submit(SmallSpec(""));
    ASSERT_TRUE(scheduler.Cancel(ended).ok());
    std::future<EndWait> waited = std::async(std::launch::async, [&] {
        return scheduler.WaitForEnd(running, absl::Now() + absl::Hours(1));
    });
    scheduler.Shutdown();
    EXPECT_EQ(waited.get(), EndWait::kShutdown);
    EXPECT_EQ(scheduler.WaitForEnd(ended, absl::InfinitePast()), EndWait::kEnded);
}

TEST(SchedulerLockTest, SubmitLooksUpItsRequestWithoutTheLock) {
    HeldStore store;
    Scheduler scheduler({}, store);
    const std::string first = *scheduler.Submit(SmallSpec(""));
    store.Hold();
    std::thread submit([&] { EXPECT_TRUE(scheduler.Submit(SmallSpec("req-1")).ok()); });
    store.AwaitBlocked();
    EXPECT_TRUE(AnsweredWhileTheStoreWaits(
        store, [&] { EXPECT_TRUE(scheduler.LeaseTask("w").has_value()); }));
    submit.join();
}

// A store whose next request lookup, once told to, answers and then waits: the submission that
// made it goes on only after the job it missed has ended and left the scheduler's memory.
class LateLookupStore : public InMemoryJobStore {
  public:
    absl::StatusOr<std::optional<std::string>> FindRequest(
        const std::string& request_id) const override {
        absl::StatusOr<std::optional<std::string>> found =
            InMemoryJobStore::FindRequest(request_id);
        std::unique_lock<std::mutex> lock(mutex_);
        if (hold_next_) {
            hold_next_ = false;
            looked_up_ = true;
            cv_.notify_all();
            cv_.wait(lock, [this] { return released_; });
        }
        return found;
    }
    void HoldNextLookup() {
        std::lock_guard<std::mutex> lock(mutex_);
        hold_next_ = true;
    }
    void AwaitLookedUp() {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return looked_up_; });
    }
    void Release() {
        std::lock_guard<std::mutex> lock(mutex_);
        released_ = true;
        cv_.notify_all();
    }

  private:
    mutable std::mutex mutex_;
    mutable std::condition_variable cv_;
    mutable bool hold_next_ = false, looked_up_ = false;
    bool released_ = false;
};

// A retried submission whose store lookup came before its first attempt was recorded, and whose
// first attempt's job ended meanwhile, still gets that job (it got AlreadyExists before).
TEST(SchedulerLockTest, RetryGetsTheFirstJobThatEndedDuringItsLookup) {
    LateLookupStore store;
    Scheduler scheduler({}, store);
    store.HoldNextLookup();
    std::future<absl::StatusOr<std::string>> retry =
        std::async(std::launch::async, [&] { return scheduler.Submit(SmallSpec("req-1")); });
    store.AwaitLookedUp();
    const absl::StatusOr<std::string> first = scheduler.Submit(SmallSpec("req-1"));
    ASSERT_TRUE(first.ok()) << first.status();
    ASSERT_TRUE(scheduler.Cancel(*first).ok());  // recorded, and gone from memory
    store.Release();
    const absl::StatusOr<std::string> again = retry.get();
    ASSERT_TRUE(again.ok()) << again.status();
    EXPECT_EQ(*again, *first);
    EXPECT_EQ(scheduler.List()->size(), 1u);
    EXPECT_FALSE(scheduler.LeaseTask("w").has_value());  // nothing of a second job queued
}

}  // namespace
}  // namespace lf
