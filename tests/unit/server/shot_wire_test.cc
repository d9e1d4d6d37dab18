// A shot on the wire and in the job store: its frames, fps, shutter and chunk reach the workers
// and the store as the client asked; a task names its frame or its chunk's parts; a job reports
// its frames. Old clients, workers and stored jobs without these fields are stills.
#include <gtest/gtest.h>

#include "lf/job/job_spec.h"
#include "lf/wire/conversions.h"
#include "lf/wire/stored_job.h"

namespace lf {
namespace {

namespace pb = lightfarm::v1;

JobSpec Shot() {
    JobSpec spec;
    spec.shot = {.frames = FrameRange{-3, 9, 4}, .fps = 30, .shutter = 0.5, .chunk = 2};
    return spec;
}

TEST(ShotWire, AShotsSettingsSurviveTheWireAndTheStore) {
    pb::RenderParams params;
    ToProto(Shot(), &params);
    JobSpec back;
    FromProto(params, &back);
    ASSERT_TRUE(back.shot.frames.has_value());
    EXPECT_EQ(*back.shot.frames, (FrameRange{-3, 9, 4}));
    EXPECT_EQ(back.shot.fps, 30);
    EXPECT_EQ(back.shot.shutter, 0.5);
    EXPECT_EQ(back.shot.chunk, 2);

    JobRecord record;
    record.spec = Shot();
    record.frames = {{.frame = -3,
                      .tasks_done = 4,
                      .tasks_total = 4,
                      .done = true,
                      .result_path = "/d/results/j.-0003.exr"},
                     {.frame = 1, .tasks_done = 1, .tasks_total = 4}};
    pb::StoredJob stored;
    ToProto(record, &stored);
    absl::StatusOr<JobRecord> restored = FromProto(stored);
    ASSERT_TRUE(restored.ok()) << restored.status();
    EXPECT_EQ(restored->spec.shot.frames, record.spec.shot.frames);
    EXPECT_EQ(restored->spec.shot.chunk, 2);
    EXPECT_EQ(restored->frames, record.frames);
    EXPECT_EQ(restored->frames_done(), 1);

    pb::Job job;
    ToProto(record, &job);
    EXPECT_EQ(job.frames_done(), 1);
    EXPECT_EQ(job.frames_total(), 4);
    ASSERT_EQ(job.frames_size(), 2);
    EXPECT_EQ(job.frames(1).frame(), 1);
    EXPECT_EQ(job.frames(1).tasks_done(), 1);
    EXPECT_FALSE(job.frames(1).done());
}

TEST(ShotWire, OldClientsAndStoredJobsAreStills) {
    JobSpec spec = Shot();
    FromProto(pb::RenderParams{}, &spec);
    EXPECT_FALSE(spec.shot.frames.has_value());
    EXPECT_EQ(spec.shot.chunk, 1);
    EXPECT_EQ(spec.shot.fps, defaults::kFps);

    pb::RenderParams still;
    ToProto(JobSpec{}, &still);
    EXPECT_FALSE(still.has_shot()) << "a still sends nothing an old worker would not know";

    pb::StoredJob old;
    old.set_state("running");
    absl::StatusOr<JobRecord> record = FromProto(old);
    ASSERT_TRUE(record.ok()) << record.status();
    EXPECT_FALSE(record->spec.shot.frames.has_value());
    EXPECT_TRUE(record->frames.empty());
    pb::Job job;
    ToProto(*record, &job);
    EXPECT_EQ(job.frames_total(), 0);
}

TEST(ShotWire, ZeroShotFieldsTakeTheDefaults) {
    pb::RenderParams params;
    params.mutable_shot()->set_first(5);
    params.mutable_shot()->set_last(5);
    JobSpec spec;
    FromProto(params, &spec);
    EXPECT_EQ(spec.shot.frames, (FrameRange{5, 5, 1}));
    EXPECT_EQ(spec.shot.fps, defaults::kFps);
    EXPECT_EQ(spec.shot.chunk, 1);
}

TEST(ShotWire, ATaskNamesItsFrameOrItsChunksParts) {
    TaskAssignment lease;
    lease.spec = Shot();
    lease.frame = 5;
    pb::Task task;
    ToProto(lease, &task);
    TaskAssignment back = FromProto(task);
    EXPECT_EQ(back.frame, 5);
    EXPECT_TRUE(back.parts.empty());

    TaskAssignment chunk;
    chunk.spec = Shot();
    chunk.task.index = 3;
    chunk.parts.push_back(
        {.frame = 1, .task = {.rect = {8, 0, 8, 4}, .sample_begin = 2, .sample_end = 6}});
    chunk.parts.push_back({.frame = 5, .path_begin = 10, .path_end = 20});
    pb::Task wire;
    ToProto(chunk, &wire);
    back = FromProto(wire);
    EXPECT_FALSE(back.frame.has_value());
    ASSERT_EQ(back.parts.size(), 2u);
    EXPECT_EQ(back.parts[0].frame, 1);
    EXPECT_EQ(back.parts[0].task.rect.x0, 8);
    EXPECT_EQ(back.parts[0].task.rect.height, 4);
    EXPECT_EQ(back.parts[0].task.sample_end, 6u);
    EXPECT_EQ(back.parts[1].path_end, 20u);

    pb::Task still;
    ToProto(TaskAssignment{}, &still);
    EXPECT_FALSE(still.has_frame());
    EXPECT_FALSE(FromProto(still).frame.has_value());
}

TEST(ShotWire, ATaskInfoNamesItsFrames) {
    TaskStatus status;
    status.frames = {3, 4};
    pb::TaskInfo info;
    ToProto(status, &info);
    ASSERT_EQ(info.frames_size(), 2);
    EXPECT_EQ(info.frames(1), 4);
}

}  // namespace
}  // namespace lf
