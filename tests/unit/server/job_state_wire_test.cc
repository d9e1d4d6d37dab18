// A job's state on the wire: the client reads back the state the server sent, and a state it
// cannot name (unset, or of a newer server) is not an end, so `watch` keeps following the job.
#include <gtest/gtest.h>

#include "lf/job/job_record.h"
#include "lf/wire/conversions.h"

namespace lf {
namespace {

namespace pb = lightfarm::v1;

TEST(JobStateWire, EachStateSurvivesTheWire) {
    for (const JobState state : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded,
                                 JobState::kFailed, JobState::kCancelled}) {
        EXPECT_EQ(FromProto(ToProto(state)), state) << JobStateName(state);
    }
}

TEST(JobStateWire, AnUnknownStateIsQueuedNotFinal) {
    for (const pb::Job::State state : {pb::Job::STATE_UNSPECIFIED, pb::Job::State(99)}) {
        EXPECT_EQ(FromProto(state), JobState::kQueued) << int(state);
        EXPECT_FALSE(IsFinal(FromProto(state))) << int(state);
    }
}

}  // namespace
}  // namespace lf
