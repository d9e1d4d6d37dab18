// The scheduler's view of a job's tasks (Scheduler::Tasks), whom a lease belongs to (HolderOf),
// and the task list handed on when a job ends (OnTasksEnded), with a fake clock.
#include <gtest/gtest.h>

#include "lease_results.h"
#include "lf/server/scheduler.h"

namespace lf {
namespace {

class SchedulerTasksTest : public ::testing::Test {
  protected:
    SchedulerTasksTest() : scheduler_(SchedulerOptions{}, store_, [this] { return now_; }) {
        scheduler_.OnTasksEnded([this](const JobRecord& ended, std::vector<TaskStatus> tasks) {
            ended_[ended.id] = std::move(tasks);
            if (requeue_when_ended_) {
                requeued_while_ending_[ended.id] = scheduler_.RequeueJob(ended.id).status();
            }
            ended_states_[ended.id] = ended.state;
        });
    }

    // A 16x8 image in 8x8 tiles, 6 spp in 2 passes: tasks 0, 1 are the left tile's passes.
    std::string Submit() {
        JobSpec spec;
        spec.name = "test";
        spec.plan = {16, 8, 6, 8, 2};
        absl::StatusOr<std::string> id = scheduler_.Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return *id;
    }

    static TileSums Result(const TaskAssignment& lease) {
        return testing::UniformResult(lease, Rgb(0.5f));
    }

    std::vector<TaskStatus> Tasks(const std::string& id) {
        std::optional<std::vector<TaskStatus>> tasks = scheduler_.Tasks(id);
        EXPECT_TRUE(tasks.has_value());
        return tasks.value_or(std::vector<TaskStatus>{});
    }

    absl::Time now_ = absl::FromUnixSeconds(1'000'000);
    InMemoryJobStore store_;
    Scheduler scheduler_;
    std::map<std::string, std::vector<TaskStatus>> ended_;
    std::map<std::string, JobState> ended_states_;  // of the record handed on
    bool requeue_when_ended_ = false;
    std::map<std::string, absl::Status> requeued_while_ending_;  // RequeueJob from the callback
};

TEST_F(SchedulerTasksTest, ShowsEachTasksStateRectangleHolderTimesAndLastError) {
    const std::string id = Submit();
    std::vector<TaskStatus> tasks = Tasks(id);
    ASSERT_EQ(tasks.size(), 4u);
    for (int t = 0; t < 4; ++t) {
        EXPECT_EQ(tasks[size_t(t)].index, t);
        EXPECT_EQ(tasks[size_t(t)].state, TaskStatus::State::kQueued);
        EXPECT_EQ(tasks[size_t(t)].kind, TaskKind::kTile);
        EXPECT_EQ(tasks[size_t(t)].samples, 3u);
        EXPECT_EQ(tasks[size_t(t)].attempts, 0);
        EXPECT_EQ(tasks[size_t(t)].worker, "");
        EXPECT_EQ(tasks[size_t(t)].leased, absl::InfinitePast());
    }

    const TaskAssignment first = *scheduler_.LeaseTask("a");
    const TaskAssignment second = *scheduler_.LeaseTask("b");
    const absl::Time leased = now_;
    now_ += absl::Seconds(3);
    ASSERT_TRUE(
        scheduler_.Fail(second.lease_id, "b", "out of memory", FailureKind::kTaskError).ok());
    tasks = Tasks(id);
    const TaskStatus& running = tasks[size_t(first.task.index)];
    EXPECT_EQ(running.state, TaskStatus::State::kRunning);
    EXPECT_EQ(running.worker, "a");
    EXPECT_EQ(running.attempts, 1);
    EXPECT_EQ(running.leased, leased);
    EXPECT_EQ(running.duration, absl::Seconds(3));
    EXPECT_EQ(running.x, first.task.rect.x0);
    EXPECT_EQ(running.width, 8);
    EXPECT_EQ(running.height, 8);
    const TaskStatus& failed = tasks[size_t(second.task.index)];
    EXPECT_EQ(failed.state, TaskStatus::State::kQueued);
    EXPECT_EQ(failed.failures, 1);
    EXPECT_EQ(failed.worker, "b");
    EXPECT_EQ(failed.last_error, "out of memory (worker b)");

    now_ += absl::Seconds(2);
    ASSERT_TRUE(scheduler_.Complete(first.lease_id, "a", Result(first)).ok());
    const TaskStatus done = Tasks(id)[size_t(first.task.index)];
    EXPECT_EQ(done.state, TaskStatus::State::kDone);
    EXPECT_EQ(done.finished, now_);
    EXPECT_EQ(done.duration, absl::Seconds(5));
}

TEST_F(SchedulerTasksTest, HolderOfNamesTheJobTaskAndAttemptOnlyForTheWorkerHoldingIt) {
    const std::string id = Submit();
    const TaskAssignment lease = *scheduler_.LeaseTask("a");
    ASSERT_TRUE(scheduler_.Fail(lease.lease_id, "a", "broken", FailureKind::kTaskError).ok());
    const TaskAssignment again = *scheduler_.LeaseTask("a");  // the only live worker
    ASSERT_EQ(again.task.index, lease.task.index);

    const std::optional<Scheduler::LeaseHolder> holder = scheduler_.HolderOf(again.lease_id, "a");
    ASSERT_TRUE(holder.has_value());
    EXPECT_EQ(holder->job_id, id);
    EXPECT_EQ(holder->task, lease.task.index);
    EXPECT_EQ(holder->attempt, 2);
    EXPECT_EQ(holder->worker, "a");
    EXPECT_TRUE(holder->current);
    // An earlier attempt still resolves, as ended (Farm::TakeTaskLog drops lines for it: a late
    // heartbeat's were stored), another worker's never.
    EXPECT_EQ(scheduler_.HolderOf(lease.lease_id, "a")->attempt, 1);
    EXPECT_FALSE(scheduler_.HolderOf(lease.lease_id, "a")->current);
    EXPECT_FALSE(scheduler_.HolderOf(again.lease_id, "b").has_value());
    EXPECT_FALSE(scheduler_.HolderOf(id + "/0/forged-1", "a").has_value());
    ASSERT_TRUE(scheduler_.Cancel(id).ok());
    EXPECT_FALSE(scheduler_.HolderOf(again.lease_id, "a").has_value());
}

TEST_F(SchedulerTasksTest, AnEndedJobsTasksAreHandedOnOnceAndLeaveMemory) {
    const std::string id = Submit();
    const TaskAssignment lease = *scheduler_.LeaseTask("a");
    now_ += absl::Seconds(1);
    ASSERT_TRUE(scheduler_.Complete(lease.lease_id, "a", Result(lease)).ok());
    EXPECT_TRUE(ended_.empty());
    ASSERT_TRUE(scheduler_.Cancel(id).ok());
    EXPECT_FALSE(scheduler_.Tasks(id).has_value());
    ASSERT_EQ(ended_.count(id), 1u);
    const std::vector<TaskStatus>& tasks = ended_[id];
    ASSERT_EQ(tasks.size(), 4u);
    EXPECT_EQ(tasks[size_t(lease.task.index)].state, TaskStatus::State::kDone);
    EXPECT_EQ(tasks[size_t(lease.task.index)].worker, "a");
    EXPECT_EQ(tasks[size_t(lease.task.index)].duration, absl::Seconds(1));
    int dropped = 0;  // never to be done
    for (const TaskStatus& t : tasks) dropped += t.state == TaskStatus::State::kDropped;
    EXPECT_EQ(dropped, 3);
}

TEST_F(SchedulerTasksTest, AFailedJobsTasksKeepTheFailingTasksLastError) {
    const std::string id = Submit();
    for (int i = 0; i < 3; ++i) {
        const TaskAssignment lease = *scheduler_.LeaseTask("a");
        ASSERT_EQ(lease.task.index, 0);
        ASSERT_TRUE(
            scheduler_.Fail(lease.lease_id, "a", "bad scene", FailureKind::kTaskError).ok());
    }
    EXPECT_EQ(scheduler_.Get(id)->state, JobState::kFailed);
    ASSERT_EQ(ended_.count(id), 1u);
    EXPECT_EQ(ended_[id][0].state, TaskStatus::State::kDropped);
    EXPECT_EQ(ended_[id][0].failures, 3);
    EXPECT_EQ(ended_[id][0].attempts, 3);
    EXPECT_EQ(ended_[id][0].last_error, "bad scene (worker a)");
}

// The callback runs before the end settles (so a client told of the end finds the tasks
// kept): a requeue from inside it is refused as "again in a moment", one once the end returned
// is taken, and the notifier's record (Farm passes it on) is the one the job ended with.
TEST_F(SchedulerTasksTest, TheEndedRecordIsTheOneTheJobEndedWithThoughRequeuedAtOnce) {
    requeue_when_ended_ = true;
    const std::string id = Submit();
    ASSERT_TRUE(scheduler_.Cancel(id).ok());
    ASSERT_EQ(ended_states_.count(id), 1u);
    EXPECT_EQ(ended_states_[id], JobState::kCancelled);
    EXPECT_EQ(requeued_while_ending_[id].code(), absl::StatusCode::kUnavailable)
        << requeued_while_ending_[id];
    requeue_when_ended_ = false;
    ASSERT_TRUE(scheduler_.RequeueJob(id).ok());
    EXPECT_EQ(scheduler_.Get(id)->state, JobState::kQueued);
    EXPECT_EQ(ended_states_[id], JobState::kCancelled);
}

}  // namespace
}  // namespace lf
