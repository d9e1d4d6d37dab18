// Job dependencies in the scheduler (issue 30): a job leases nothing while a job it runs after
// is queued or running, says so in its waiting reason, and fails (down a chain, each notified
// as an ended job) when a dependency fails or is cancelled, not when an ended one is deleted;
// `depend` refuses a cycle; a dependency that ended before a restart is seen by Recover.
#include <gtest/gtest.h>

#include <set>

#include "lease_results.h"
#include "lf/server/scheduler.h"

namespace lf {
namespace {

class SchedulerDependencies : public ::testing::Test {
  protected:
    SchedulerDependencies() : scheduler_(SchedulerOptions{}, store_, [this] { return now_; }) {
        scheduler_.OnTasksEnded(
            [this](const JobRecord& job, std::vector<TaskStatus>) { ended_.push_back(job.id); });
    }

    // One task (16x16 in one tile), running after `after`.
    absl::StatusOr<std::string> Submit(std::vector<std::string> after = {}) {
        JobSpec spec;
        spec.name = "dependent";
        spec.plan = {16, 16, 1, 16, 1};
        spec.max_attempts = 1;
        spec.after = std::move(after);
        return scheduler_.Submit(spec);
    }

    std::string MustSubmit(std::vector<std::string> after = {}) {
        absl::StatusOr<std::string> id = Submit(std::move(after));
        EXPECT_TRUE(id.ok()) << id.status();
        return id.value_or("");
    }

    std::optional<TaskAssignment> Lease() {
        return scheduler_.LeaseTask("w-1", absl::InfinitePast());
    }

    // Leases and completes the job's one task, then finishes it as the farm would.
    void Run(const std::string& id) {
        std::optional<TaskAssignment> lease = Lease();
        ASSERT_TRUE(lease.has_value()) << "nothing to lease; " << id << " expected";
        ASSERT_EQ(lease->job_id, id);
        absl::StatusOr<Scheduler::Completion> done =
            scheduler_.Complete(lease->lease_id, "w-1", testing::UniformResult(*lease, Rgb(0.5f)));
        ASSERT_TRUE(done.ok()) << done.status();
        ASSERT_TRUE(done->job_rendered);
        scheduler_.Finish({id, done->run}, "/results/" + id + ".exr");
    }

    JobRecord Get(const std::string& id) {
        absl::StatusOr<JobRecord> job = scheduler_.Get(id);
        EXPECT_TRUE(job.ok()) << job.status();
        return job.value_or(JobRecord{});
    }

    absl::Time now_ = absl::FromUnixSeconds(1'000'000);
    InMemoryJobStore store_;
    Scheduler scheduler_;
    std::vector<std::string> ended_;  // as OnTasksEnded (the notifier's cue) heard them
};

TEST_F(SchedulerDependencies, ChainRunsInOrderAndSaysWhatItWaitsFor) {
    const std::string a = MustSubmit();
    const std::string b = MustSubmit({a});
    const std::string c = MustSubmit({b, b});
    EXPECT_EQ(Get(c).spec.after, std::vector<std::string>{b}) << "duplicates collapse";
    EXPECT_EQ(Get(b).waiting_reason, "waiting for " + a + " (queued)");
    EXPECT_EQ(Get(b).waiting_for, std::vector<std::string>{a});
    std::optional<TaskAssignment> first = Lease();
    ASSERT_TRUE(first.has_value());
    EXPECT_EQ(first->job_id, a);
    EXPECT_FALSE(Lease().has_value()) << "B and C wait while A runs";
    EXPECT_EQ(Get(b).waiting_reason, "waiting for " + a + " (running)");
    EXPECT_EQ(Get(b).state, JobState::kQueued);
    absl::StatusOr<Scheduler::Completion> rendered =
        scheduler_.Complete(first->lease_id, "w-1", testing::UniformResult(*first, Rgb(0.5f)));
    ASSERT_TRUE(rendered.ok()) << rendered.status();
    EXPECT_FALSE(Lease().has_value()) << "A rendered is not A succeeded";
    now_ += absl::Seconds(1);
    scheduler_.Finish({a, rendered->run}, "/results/a.exr");
    EXPECT_TRUE(Get(b).waiting_reason.empty());
    EXPECT_TRUE(Get(b).waiting_for.empty());
    now_ += absl::Seconds(1);
    Run(b);
    now_ += absl::Seconds(1);
    Run(c);
    const JobRecord ra = Get(a), rb = Get(b), rc = Get(c);
    for (const JobRecord* r : {&ra, &rb, &rc}) EXPECT_EQ(r->state, JobState::kSucceeded) << r->id;
    EXPECT_LT(ra.finished, rb.started);
    EXPECT_LT(rb.finished, rc.started);
    EXPECT_EQ(ended_, (std::vector<std::string>{a, b, c}));
}

TEST_F(SchedulerDependencies, SubmitRefusesUnknownAndFailedDependencies) {
    const absl::Status unknown = Submit({"job-nonesuch"}).status();
    EXPECT_TRUE(absl::IsNotFound(unknown)) << unknown;
    EXPECT_NE(unknown.message().find("job-nonesuch"), std::string::npos) << unknown;
    const std::string a = MustSubmit();
    ASSERT_TRUE(scheduler_.Cancel(a).ok());
    const absl::Status cancelled = Submit({a}).status();
    EXPECT_TRUE(absl::IsFailedPrecondition(cancelled)) << cancelled;
    EXPECT_NE(cancelled.message().find(a + " has already ended (cancelled)"), std::string::npos)
        << cancelled;
    const std::string done = MustSubmit();
    Run(done);
    const std::string b = MustSubmit({done});
    EXPECT_TRUE(Get(b).waiting_for.empty()) << "a succeeded dependency is satisfied";
    Run(b);
}

TEST_F(SchedulerDependencies, FailureFailsTheChainBelow) {
    const std::string a = MustSubmit();
    const std::string b = MustSubmit({a});
    const std::string c = MustSubmit({b});
    const std::string other = MustSubmit();
    std::optional<TaskAssignment> lease = Lease();
    ASSERT_TRUE(lease && lease->job_id == a);
    ASSERT_TRUE(scheduler_.Fail(lease->lease_id, "w-1", "boom", FailureKind::kTaskError).ok());
    ASSERT_EQ(Get(a).state, JobState::kFailed);
    EXPECT_EQ(Get(b).state, JobState::kFailed);
    EXPECT_EQ(Get(b).error, "dependency " + a + " failed: " + Get(a).error);
    EXPECT_EQ(Get(c).state, JobState::kFailed);
    EXPECT_EQ(Get(c).error, "dependency " + b + " failed: " + Get(b).error);
    EXPECT_EQ(std::set<std::string>(ended_.begin(), ended_.end()), (std::set<std::string>{a, b, c}))
        << "each dependent is notified as an ended job";
    EXPECT_EQ(Get(other).state, JobState::kQueued) << "a job not depending on A goes on";
}

TEST_F(SchedulerDependencies, CancelFailsTheDependents) {
    const std::string a = MustSubmit();
    const std::string b = MustSubmit({a});
    ASSERT_TRUE(scheduler_.Cancel(a).ok());
    EXPECT_EQ(Get(b).state, JobState::kFailed);
    EXPECT_EQ(Get(b).error, "dependency " + a + " was cancelled");
}

// A dependent failed with its dependency is refused a requeue while that dependency stays
// failed (nothing changes: it would only fail again), and taken once the dependency runs again.
TEST_F(SchedulerDependencies, RequeueOfADependentWaitsForItsDependencysRequeue) {
    const std::string a = MustSubmit();
    const std::string b = MustSubmit({a});
    ASSERT_TRUE(scheduler_.Cancel(a).ok());
    ASSERT_EQ(Get(b).state, JobState::kFailed);
    const absl::StatusOr<Scheduler::Requeued> refused = scheduler_.RequeueJob(b);
    ASSERT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(refused.status().message(), "job " + b + " cannot run: dependency " + a +
                                              " was cancelled; requeue that one first");
    EXPECT_EQ(Get(b).state, JobState::kFailed);
    EXPECT_EQ(Get(b).error, "dependency " + a + " was cancelled") << "the refusal changed it";
    ASSERT_TRUE(scheduler_.RequeueJob(a).ok());
    ASSERT_TRUE(scheduler_.RequeueJob(b).ok());
    EXPECT_EQ(Get(b).waiting_for, std::vector<std::string>{a});
    Run(a);
    Run(b);
    EXPECT_EQ(Get(b).state, JobState::kSucceeded);
}

// A job is deleted only once ended, its dependents settled then: deleting it afterwards leaves a
// failed dependent failed with its reason, and a requeue of that dependent (the user's call)
// finds nothing left to wait for; a dependent released by a success is not failed by a delete.
TEST_F(SchedulerDependencies, DeletingAnEndedDependencyChangesNothing) {
    const std::string a = MustSubmit();
    const std::string b = MustSubmit({a});
    ASSERT_TRUE(scheduler_.Cancel(a).ok());
    ASSERT_EQ(Get(b).state, JobState::kFailed);
    ASSERT_TRUE(store_.Delete(a).ok());
    EXPECT_EQ(Get(b).error, "dependency " + a + " was cancelled");
    absl::StatusOr<Scheduler::Requeued> requeued = scheduler_.RequeueJob(b);
    ASSERT_TRUE(requeued.ok()) << requeued.status();
    EXPECT_EQ(requeued->record.state, JobState::kQueued);
    Run(b);

    const std::string c = MustSubmit();
    const std::string d = MustSubmit({c});
    Run(c);
    ASSERT_TRUE(store_.Delete(c).ok());  // as retention would
    Run(d);
}

TEST_F(SchedulerDependencies, DependRefusesCyclesAndAddsToQueuedJobsOnly) {
    const std::string a = MustSubmit();
    const std::string b = MustSubmit({a});
    const std::string c = MustSubmit({b});
    const absl::Status cycle = scheduler_.AddDependencies(a, {c}).status();
    EXPECT_TRUE(absl::IsFailedPrecondition(cycle)) << cycle;
    EXPECT_EQ(cycle.message(), "cycle: " + a + " -> " + c + " -> " + b + " -> " + a);
    const absl::Status self = scheduler_.AddDependencies(a, {a}).status();
    EXPECT_TRUE(absl::IsFailedPrecondition(self)) << self;
    EXPECT_TRUE(absl::IsNotFound(scheduler_.AddDependencies(a, {"job-nonesuch"}).status()));

    const std::string d = MustSubmit();
    absl::StatusOr<JobRecord> added = scheduler_.AddDependencies(a, {d, d});
    ASSERT_TRUE(added.ok()) << added.status();
    EXPECT_EQ(added->spec.after, std::vector<std::string>{d});
    EXPECT_EQ(added->waiting_reason, "waiting for " + d + " (queued)");
    std::optional<TaskAssignment> lease = Lease();
    ASSERT_TRUE(lease.has_value());
    EXPECT_EQ(lease->job_id, d) << "A now waits for D";
    const absl::Status running = scheduler_.AddDependencies(d, {c}).status();
    EXPECT_TRUE(absl::IsFailedPrecondition(running)) << running;
    EXPECT_NE(running.message().find("running"), std::string::npos) << running;
}

TEST_F(SchedulerDependencies, RecoverStillWaitsAndSeesWhatEndedMeanwhile) {
    // What a restart may find: C's dependency succeeded and then deleted (by retention, say)
    // before C was leased, and a job whose dependency's failure was recorded, its own not yet.
    const std::string gone = MustSubmit();
    Run(gone);
    const std::string a = MustSubmit();
    const std::string b = MustSubmit({a});
    const std::string c = MustSubmit({gone});
    ASSERT_TRUE(store_.Delete(gone).ok());
    JobRecord failed = Get(a);
    failed.id = "job-failedbefore";
    failed.state = JobState::kFailed;
    failed.error = "it broke";
    ASSERT_TRUE(store_.Put(failed).ok());
    JobRecord orphan = Get(b);
    orphan.id = "job-orphan";
    orphan.seq = 99;
    orphan.spec.after = {failed.id};
    ASSERT_TRUE(store_.Put(orphan).ok());

    Scheduler restarted(SchedulerOptions{}, store_, [this] { return now_; });
    ASSERT_TRUE(restarted.Recover().ok());
    EXPECT_EQ(restarted.Get(c)->state, JobState::kQueued) << "released before the restart";
    EXPECT_TRUE(restarted.Get(c)->waiting_for.empty());
    EXPECT_EQ(restarted.Get(orphan.id)->error, "dependency job-failedbefore failed: it broke");
    EXPECT_EQ(restarted.Get(b)->waiting_for, std::vector<std::string>{a});
    ASSERT_TRUE(restarted.Cancel(c).ok());
    std::optional<TaskAssignment> lease = restarted.LeaseTask("w-1", absl::InfinitePast());
    ASSERT_TRUE(lease.has_value());
    EXPECT_EQ(lease->job_id, a);
    EXPECT_FALSE(restarted.LeaseTask("w-1", absl::InfinitePast()).has_value());
    absl::StatusOr<Scheduler::Completion> rendered =
        restarted.Complete(lease->lease_id, "w-1", testing::UniformResult(*lease, Rgb(0.5f)));
    ASSERT_TRUE(rendered.ok()) << rendered.status();
    restarted.Finish({a, rendered->run}, "/results/a.exr");
    lease = restarted.LeaseTask("w-1", absl::InfinitePast());
    ASSERT_TRUE(lease.has_value());
    EXPECT_EQ(lease->job_id, b) << "released once its dependency succeeded";
}

}  // namespace
}  // namespace lf
