// The job state machine: final states have no way out, and the times it stamps.
#include "lf/server/job_state_machine.h"

#include <gtest/gtest.h>

namespace lf {
namespace {

const absl::Time kT0 = absl::FromUnixSeconds(1000);
constexpr JobState kAll[] = {JobState::kQueued, JobState::kRunning, JobState::kSucceeded,
                             JobState::kFailed, JobState::kCancelled};

TEST(JobStateMachine, FinalStatesHaveNoWayOut) {
    for (JobState from : kAll) {
        for (JobState to : kAll) {
            if (IsFinal(from)) {
                EXPECT_FALSE(IsLegalJobTransition(from, to))
                    << JobStateName(from) << " -> " << JobStateName(to);
            }
        }
    }
    EXPECT_FALSE(IsLegalJobTransition(JobState::kRunning, JobState::kQueued));
    EXPECT_FALSE(IsLegalJobTransition(JobState::kQueued, JobState::kSucceeded));  // nothing ran
    EXPECT_TRUE(IsLegalJobTransition(JobState::kQueued, JobState::kCancelled));
    EXPECT_TRUE(IsLegalJobTransition(JobState::kRunning, JobState::kFailed));
}

TEST(JobStateMachine, StampsStartAndEndAndRefusesIllegalMoves) {
    JobRecord job;
    job.id = "job-1";
    ASSERT_TRUE(TransitionJob(job, JobState::kRunning, kT0).ok());
    EXPECT_EQ(job.started, kT0);
    EXPECT_EQ(job.finished, absl::InfinitePast());
    ASSERT_TRUE(TransitionJob(job, JobState::kCancelled, kT0 + absl::Seconds(2)).ok());
    EXPECT_EQ(job.finished, kT0 + absl::Seconds(2));
    const absl::Status again = TransitionJob(job, JobState::kRunning, kT0 + absl::Seconds(3));
    EXPECT_EQ(again.code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(again.message().find("job-1"), std::string::npos) << again;
    EXPECT_EQ(job.state, JobState::kCancelled);
    EXPECT_EQ(job.started, kT0);
}

TEST(JobStateMachine, CancelledWhileQueuedNeverStarted) {
    JobRecord job;
    ASSERT_TRUE(TransitionJob(job, JobState::kCancelled, kT0).ok());
    EXPECT_EQ(job.started, absl::InfinitePast());
    EXPECT_EQ(job.finished, kT0);
}

}  // namespace
}  // namespace lf
