// A shot through the coordinator's Farm, with made-up results (no renderer): each frame's EXR is
// written as soon as its last task merges, with the frame's header; a cancelled shot keeps its
// finished frames fetchable; a restarted coordinator replays the recorded results frame by frame
// and finishes the shot; deleting it removes every frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "lf/core/image_io.h"
#include "lf/core/tile_codec.h"
#include "lf/job/digest.h"
#include "lf/server/farm.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class ShotFarmTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_shotfarm");
        options_.data_dir = dir_.string();
        Open();
        std::ifstream in(fs::path(LF_TEST_SCENES) / "cornell_box.json");
        std::stringstream text;
        text << in.rdbuf();
        scene_ = text.str();
        auto upload = farm_->blobs().StartUpload(Sha256Hex(scene_), scene_.size());
        ASSERT_TRUE(upload.ok()) << upload.status();
        ASSERT_TRUE((*upload)->Append(scene_).ok());
        ASSERT_TRUE((*upload)->Finish().ok());
    }
    void TearDown() override {
        farm_.reset();
        fs::remove_all(dir_);
    }

    void Open() {
        farm_.reset();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options_);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
    }

    JobSpec Shot(int chunk = 1) {
        JobSpec spec;
        spec.scene = {"scene.json", Sha256Hex(scene_), scene_.size()};
        spec.scene_options.width = 16;  // 4 tiles of 8x8 a frame
        spec.scene_options.height = 16;
        spec.plan.spp = 2;
        spec.plan.tile = 8;
        spec.plan.passes = 1;
        spec.shot.frames = FrameRange{1, 3, 1};
        spec.shot.chunk = chunk;
        return spec;
    }

    // Leases one task and answers it with every sample at the frame's number / 10.
    void RenderOne() {
        std::optional<TaskAssignment> lease =
            farm_->scheduler().LeaseTask("w1", absl::Now() + absl::Seconds(5));
        ASSERT_TRUE(lease.has_value());
        Answer(*lease);
    }
    // The frame's number / 10 at every sample; with `noise`, plus or minus 0.05 sample by sample
    // (the mean the same), so that an adaptive plan wants more passes.
    void Answer(const TaskAssignment& assignment, bool noise = false) {
        const TaskAssignment* lease = &assignment;
        const auto sums = [noise](const RenderTask& task, int frame) {
            TileSums s(task.rect);
            for (PixelSums& p : s.pixels) {
                for (uint64_t i = task.sample_begin; i < task.sample_end; ++i) {
                    const float wobble = noise ? (i % 2 ? 0.05f : -0.05f) : 0.0f;
                    p.Add(i, Rgb(float(frame) / 10 + wobble));
                }
            }
            return EncodeTileSums(s);
        };
        if (lease->parts.empty()) {
            ASSERT_TRUE(lease->frame.has_value());
            const absl::Status s =
                farm_->Complete(lease->lease_id, "w1", sums(lease->task, *lease->frame),
                                std::nullopt, std::nullopt, lease->frame);
            ASSERT_TRUE(s.ok()) << s;
            return;
        }
        std::vector<std::string> encoded;
        for (const TaskAssignment::Part& part : lease->parts) {
            encoded.push_back(sums(part.task, part.frame));
        }
        std::vector<Farm::ResultPart> parts;
        for (size_t i = 0; i < encoded.size(); ++i) {
            parts.push_back({lease->parts[i].frame, encoded[i], std::nullopt});
        }
        const absl::Status s = farm_->Complete(lease->lease_id, "w1", "", std::nullopt,
                                               std::nullopt, std::nullopt, parts);
        ASSERT_TRUE(s.ok()) << s;
    }

    // The frame's EXR: its R at (0, 0) and its lightfarm.frame attribute.
    void ExpectFrame(const std::string& job, int frame) {
        absl::StatusOr<std::string> path = farm_->ResultFile(job, false, frame);
        ASSERT_TRUE(path.ok()) << path.status();
        absl::StatusOr<ExrFile> exr = ReadExr(*path);
        ASSERT_TRUE(exr.ok()) << exr.status();
        EXPECT_FLOAT_EQ(exr->image.FindChannel("R")->at(0), float(frame) / 10) << frame;
        ASSERT_TRUE(exr->attributes.count("lightfarm.frame")) << frame;
    }

    fs::path dir_;
    FarmOptions options_;
    std::string scene_;
    std::unique_ptr<Farm> farm_;
};

TEST_F(ShotFarmTest, EachFrameIsWrittenWhenItCompletesAndACancelledShotKeepsThem) {
    absl::StatusOr<std::string> job = farm_->Submit(Shot());
    ASSERT_TRUE(job.ok()) << job.status();
    for (int t = 0; t < 4; ++t) RenderOne();  // frame 1
    absl::StatusOr<JobRecord> record = farm_->scheduler().Get(*job);
    ASSERT_TRUE(record.ok());
    EXPECT_EQ(record->frames_done(), 1);
    ASSERT_EQ(record->frames.size(), 3u);
    EXPECT_FALSE(record->frames[0].result_path.empty());
    ExpectFrame(*job, 1);
    RenderOne();  // a tile of frame 2
    EXPECT_EQ(farm_->ResultFile(*job, false, 2).status().code(),
              absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(farm_->ResultFile(*job, false).status().code(), absl::StatusCode::kFailedPrecondition)
        << "a shot is fetched frame by frame";
    EXPECT_EQ(farm_->ResultFile(*job, false, 7).status().code(), absl::StatusCode::kNotFound);
    absl::StatusOr<std::string> preview = farm_->ResultFile(*job, true, 2);
    ASSERT_TRUE(preview.ok()) << preview.status();

    ASSERT_TRUE(farm_->scheduler().Cancel(*job).ok());
    ExpectFrame(*job, 1);
    EXPECT_EQ(farm_->ResultFile(*job, false, 2).status().code(),
              absl::StatusCode::kFailedPrecondition);
    Open();  // and from the store, once the coordinator restarted
    ExpectFrame(*job, 1);

    const std::string frame_file = *farm_->ResultFile(*job, false, 1);
    ASSERT_TRUE(farm_->DeleteJob(*job).ok());
    EXPECT_FALSE(fs::exists(frame_file));
}

TEST_F(ShotFarmTest, ARestartedCoordinatorReplaysTheFramesAndFinishesTheShot) {
    absl::StatusOr<std::string> job = farm_->Submit(Shot());
    ASSERT_TRUE(job.ok()) << job.status();
    for (int t = 0; t < 6; ++t) RenderOne();  // frame 1, half of frame 2
    Open();
    absl::StatusOr<JobRecord> record = farm_->scheduler().Get(*job);
    ASSERT_TRUE(record.ok()) << record.status();
    EXPECT_EQ(record->tasks_done, 6);
    ASSERT_EQ(record->frames.size(), 3u);
    EXPECT_EQ(record->frames[1].tasks_done, 2);
    ExpectFrame(*job, 1);
    for (int t = 0; t < 6; ++t) RenderOne();
    record = farm_->scheduler().Get(*job);
    ASSERT_TRUE(record.ok());
    EXPECT_EQ(record->state, JobState::kSucceeded) << record->error;
    EXPECT_EQ(record->frames_done(), 3);
    for (int f : {1, 2, 3}) ExpectFrame(*job, f);
}

// An adaptive shot appends each frame's next passes as the frame's results merge; here frame 2's
// first passes merge before frame 1's, so frame 2's next pass takes a shot task index before
// frame 1's. A restarted coordinator replays the results in the order they merged, so every
// recorded index means the frame's task it meant, and the shot finishes with each frame's value.
TEST_F(ShotFarmTest, AnAdaptiveShotReplaysItsPassesAsTheyMergedAcrossFrames) {
    JobSpec spec = Shot();
    spec.shot.frames = FrameRange{1, 2, 1};
    spec.plan.spp = 4;
    spec.adaptive.target_error = 1e-4;  // far below the noise: passes up to max_spp
    spec.adaptive.max_spp = 16;
    absl::StatusOr<std::string> job = farm_->Submit(spec);
    ASSERT_TRUE(job.ok()) << job.status();
    std::vector<TaskAssignment> first;  // every first pass: 4 tiles a frame
    while (std::optional<TaskAssignment> lease =
               farm_->scheduler().LeaseTask("w1", absl::Now() + absl::Milliseconds(100))) {
        first.push_back(*lease);
    }
    ASSERT_EQ(first.size(), 8u);
    std::stable_sort(first.begin(), first.end(),
                     [](const TaskAssignment& a, const TaskAssignment& b) {
                         return *a.frame > *b.frame;  // frame 2 first
                     });
    for (const TaskAssignment& lease : first) Answer(lease, true);
    absl::StatusOr<JobRecord> before = farm_->scheduler().Get(*job);
    ASSERT_TRUE(before.ok());
    ASSERT_GT(before->tasks_total, 8) << "no pass appended";
    std::vector<TaskAssignment> second;  // a few of the appended passes
    for (int i = 0; i < 3; ++i) {
        std::optional<TaskAssignment> lease =
            farm_->scheduler().LeaseTask("w1", absl::Now() + absl::Seconds(5));
        ASSERT_TRUE(lease.has_value());
        Answer(*lease, true);
    }
    before = farm_->scheduler().Get(*job);
    ASSERT_TRUE(before.ok());
    Open();
    absl::StatusOr<JobRecord> after = farm_->scheduler().Get(*job);
    ASSERT_TRUE(after.ok()) << after.status();
    EXPECT_EQ(after->tasks_done, before->tasks_done) << "recorded results were refused";
    EXPECT_EQ(after->tasks_total, before->tasks_total);
    while (std::optional<TaskAssignment> lease =
               farm_->scheduler().LeaseTask("w1", absl::Now() + absl::Milliseconds(200))) {
        Answer(*lease, true);
    }
    after = farm_->scheduler().Get(*job);
    ASSERT_TRUE(after.ok());
    EXPECT_EQ(after->state, JobState::kSucceeded) << after->error;
    for (int f : {1, 2}) {
        absl::StatusOr<std::string> path = farm_->ResultFile(*job, false, f);
        ASSERT_TRUE(path.ok()) << path.status();
        absl::StatusOr<ExrFile> exr = ReadExr(*path);
        ASSERT_TRUE(exr.ok()) << exr.status();
        // An even number of samples a pixel: the wobble cancels.
        EXPECT_NEAR(exr->image.FindChannel("R")->at(0), float(f) / 10, 1e-5) << f;
    }
}

TEST_F(ShotFarmTest, ChunksOfWholeFramesAcrossARestart) {
    absl::StatusOr<std::string> job = farm_->Submit(Shot(2));  // {1, 2}, {3}
    ASSERT_TRUE(job.ok()) << job.status();
    RenderOne();
    absl::StatusOr<JobRecord> record = farm_->scheduler().Get(*job);
    ASSERT_TRUE(record.ok());
    EXPECT_EQ(record->tasks_total, 2);
    EXPECT_EQ(record->frames_done(), 2);
    Open();
    ExpectFrame(*job, 2);
    RenderOne();
    record = farm_->scheduler().Get(*job);
    ASSERT_TRUE(record.ok());
    EXPECT_EQ(record->state, JobState::kSucceeded) << record->error;
    for (int f : {1, 2, 3}) ExpectFrame(*job, f);
}

// A chunk's result must hold its task's parts, counted before any is decoded; one refused half
// way keeps the parts merged before the refusal, and the frames they complete are written at
// once, so a shot cancelled before the retry keeps them.
TEST_F(ShotFarmTest, AChunkRefusedHalfWayWritesTheFramesItCompleted) {
    absl::StatusOr<std::string> job = farm_->Submit(Shot(2));  // {1, 2}, {3}
    ASSERT_TRUE(job.ok()) << job.status();
    std::optional<TaskAssignment> lease =
        farm_->scheduler().LeaseTask("w1", absl::Now() + absl::Seconds(5));
    ASSERT_TRUE(lease.has_value());
    ASSERT_EQ(lease->parts.size(), 8u);  // 4 tiles of frame 1, then of frame 2
    std::vector<std::string> encoded;
    for (const TaskAssignment::Part& part : lease->parts) {
        TileSums sums(part.task.rect);
        for (PixelSums& p : sums.pixels) {
            for (uint64_t i = part.task.sample_begin; i < part.task.sample_end; ++i) {
                p.Add(i, Rgb(float(part.frame) / 10));
            }
        }
        encoded.push_back(EncodeTileSums(sums));
    }
    std::vector<Farm::ResultPart> parts;
    for (size_t i = 0; i < encoded.size(); ++i) {
        parts.push_back({lease->parts[i].frame, encoded[i], std::nullopt});
    }
    const std::vector<Farm::ResultPart> three(parts.begin(), parts.begin() + 3);
    absl::Status s =
        farm_->Complete(lease->lease_id, "w1", "", std::nullopt, std::nullopt, std::nullopt, three);
    EXPECT_NE(s.message().find("3 parts in the result of a task of 8 parts"),
              std::string_view::npos)
        << s;
    lease = farm_->scheduler().LeaseTask("w1", absl::Now() + absl::Seconds(5));
    ASSERT_TRUE(lease.has_value());
    std::vector<Farm::ResultPart> damaged = parts;
    damaged[5].tile_sums = encoded[0];  // frame 2's second tile with another rectangle
    s = farm_->Complete(lease->lease_id, "w1", "", std::nullopt, std::nullopt, std::nullopt,
                        damaged);
    EXPECT_FALSE(s.ok());
    ASSERT_TRUE(farm_->scheduler().Cancel(*job).ok());
    ExpectFrame(*job, 1);
    EXPECT_FALSE(farm_->ResultFile(*job, false, 2).ok());
    // A chunk's result after its job ended is refused as the lease it no longer is, not for
    // its parts (the ended job's task has none).
    s = farm_->Complete(lease->lease_id, "w1", "", std::nullopt, std::nullopt, std::nullopt, parts);
    EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << s;
    EXPECT_NE(s.message().find("is not one of worker w1 in a running job"), std::string_view::npos)
        << s;
}

TEST_F(ShotFarmTest, BadShotSettingsAreRefusedAtSubmissionWithRendersMessage) {
    JobSpec spec = Shot();
    spec.shot.fps = -1;
    absl::StatusOr<std::string> job = farm_->Submit(spec);
    ASSERT_FALSE(job.ok());
    EXPECT_EQ(job.status(), CheckJobSettings(spec));
    spec = Shot(2);
    spec.adaptive.target_error = 0.05;
    job = farm_->Submit(spec);
    ASSERT_FALSE(job.ok());
    EXPECT_NE(job.status().message().find("--chunk 1"), std::string::npos) << job.status();
}

// `lightfarm requeue --frames`: a succeeded shot's chosen frames are rendered again from scratch
// (their EXRs dropped, the other frames kept), durably across a restart, and the shot succeeds
// again; frames outside the shot, a still and a running job are refused.
TEST_F(ShotFarmTest, RequeuedFramesOfASucceededShotAreRenderedAgainAcrossARestart) {
    absl::StatusOr<std::string> job = farm_->Submit(Shot());
    ASSERT_TRUE(job.ok()) << job.status();
    EXPECT_EQ(farm_->Requeue(*job, FrameRange{2, 2, 1}).status().code(),
              absl::StatusCode::kFailedPrecondition)
        << "a queued job";
    for (int t = 0; t < 12; ++t) RenderOne();
    ASSERT_EQ(farm_->scheduler().Get(*job)->state, JobState::kSucceeded);
    const std::string frame_2 = *farm_->ResultFile(*job, false, 2);

    const absl::Status outside = farm_->Requeue(*job, FrameRange{2, 6, 2}).status();
    EXPECT_EQ(outside.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(outside.message().find("frames 4, 6 not in job"), std::string::npos) << outside;
    JobSpec still = Shot();
    still.shot.frames.reset();
    absl::StatusOr<std::string> image = farm_->Submit(still);
    ASSERT_TRUE(image.ok()) << image.status();
    ASSERT_TRUE(farm_->scheduler().Cancel(*image).ok());
    const absl::Status of_still = farm_->Requeue(*image, FrameRange{1, 1, 1}).status();
    EXPECT_EQ(of_still.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(of_still.message().find("still image"), std::string::npos) << of_still;
    EXPECT_EQ(farm_->scheduler().Get(*job)->state, JobState::kSucceeded)
        << "refusals change nothing";

    absl::StatusOr<JobRecord> requeued = farm_->Requeue(*job, FrameRange{2, 2, 1});
    ASSERT_TRUE(requeued.ok()) << requeued.status();
    EXPECT_EQ(requeued->state, JobState::kQueued);
    EXPECT_EQ(requeued->tasks_done, 8);
    EXPECT_FALSE(fs::exists(frame_2));
    EXPECT_EQ(farm_->ResultFile(*job, false, 2).status().code(),
              absl::StatusCode::kFailedPrecondition);
    Open();  // durable: the restarted coordinator renders frame 2 alone
    absl::StatusOr<JobRecord> record = farm_->scheduler().Get(*job);
    ASSERT_TRUE(record.ok()) << record.status();
    EXPECT_EQ(record->state, JobState::kQueued);
    EXPECT_EQ(record->tasks_done, 8);
    ExpectFrame(*job, 1);
    ExpectFrame(*job, 3);
    for (int t = 0; t < 4; ++t) {
        std::optional<TaskAssignment> lease =
            farm_->scheduler().LeaseTask("w1", absl::Now() + absl::Seconds(5));
        ASSERT_TRUE(lease.has_value());
        EXPECT_EQ(lease->frame, std::optional<int>(2));
        Answer(*lease);
    }
    record = farm_->scheduler().Get(*job);
    ASSERT_TRUE(record.ok());
    EXPECT_EQ(record->state, JobState::kSucceeded) << record->error;
    for (int f : {1, 2, 3}) ExpectFrame(*job, f);
}

// A frame's record from an earlier run (as the farm's write of frame 2 would make it, finishing
// after `requeue --frames 2`) is not taken by the run queued again, which renders it itself.
TEST_F(ShotFarmTest, AFrameWrittenForAnEndedRunIsNotRecordedInTheRunQueuedAgain) {
    absl::StatusOr<std::string> job = farm_->Submit(Shot());
    ASSERT_TRUE(job.ok()) << job.status();
    for (int t = 0; t < 11; ++t) RenderOne();
    const std::optional<uint64_t> earlier = farm_->scheduler().RunOf(*job);
    ASSERT_TRUE(earlier.has_value());
    RenderOne();
    ASSERT_EQ(farm_->scheduler().Get(*job)->state, JobState::kSucceeded);
    EXPECT_FALSE(farm_->scheduler().RunOf(*job).has_value()) << "an ended job has no run";
    const std::string frame_2 = *farm_->ResultFile(*job, false, 2);
    ASSERT_TRUE(farm_->Requeue(*job, FrameRange{2, 2, 1}).ok());
    const std::optional<uint64_t> again = farm_->scheduler().RunOf(*job);
    ASSERT_TRUE(again.has_value());
    EXPECT_NE(*again, *earlier);
    EXPECT_FALSE(farm_->scheduler().FrameWritten({*job, *earlier}, 2, frame_2));
    EXPECT_TRUE(farm_->scheduler().Get(*job)->frames[1].result_path.empty());
    EXPECT_EQ(farm_->ResultFile(*job, false, 2).status().code(),
              absl::StatusCode::kFailedPrecondition);
    EXPECT_FALSE(farm_->scheduler().FrameWritten({*job, *earlier}, 2, absl::InternalError("disk")));
    EXPECT_EQ(farm_->scheduler().Get(*job)->state, JobState::kQueued) << "nor fails it";
}

// A chunk holds several frames: requeuing one renders its chunk again, and says which frames.
// A job released by the shot's success would wait for it again mid-render (and a cycle could
// close through it): the shot's frames are refused a requeue while such a job is queued or
// running.
TEST_F(ShotFarmTest, FramesOfAShotOthersRunAfterAreRefusedARequeueUntilTheyEnd) {
    absl::StatusOr<std::string> shot = farm_->Submit(Shot());
    ASSERT_TRUE(shot.ok()) << shot.status();
    for (int t = 0; t < 12; ++t) RenderOne();
    ASSERT_EQ(farm_->scheduler().Get(*shot)->state, JobState::kSucceeded);
    JobSpec comp = Shot();
    comp.after = {*shot};
    absl::StatusOr<std::string> after = farm_->Submit(comp);
    ASSERT_TRUE(after.ok()) << after.status();
    const absl::Status refused = farm_->Requeue(*shot, FrameRange{2, 2, 1}).status();
    EXPECT_EQ(refused.code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(refused.message().find("has jobs running after it (" + *after + ")"),
              std::string::npos)
        << refused;
    EXPECT_EQ(farm_->scheduler().Get(*shot)->state, JobState::kSucceeded);
    ASSERT_TRUE(farm_->scheduler().Cancel(*after).ok());
    EXPECT_TRUE(farm_->Requeue(*shot, FrameRange{2, 2, 1}).ok());
}

TEST_F(ShotFarmTest, RequeuingAFrameOfAChunkRendersTheChunkAgain) {
    absl::StatusOr<std::string> job = farm_->Submit(Shot(2));  // chunks {1, 2} and {3}
    ASSERT_TRUE(job.ok()) << job.status();
    for (int t = 0; t < 2; ++t) RenderOne();
    ASSERT_EQ(farm_->scheduler().Get(*job)->state, JobState::kSucceeded);
    absl::StatusOr<JobRecord> requeued = farm_->Requeue(*job, FrameRange{2, 2, 1});
    ASSERT_TRUE(requeued.ok()) << requeued.status();
    ASSERT_EQ(requeued->frames.size(), 3u);
    EXPECT_TRUE(requeued->frames[0].result_path.empty());
    EXPECT_TRUE(requeued->frames[1].result_path.empty());
    EXPECT_FALSE(requeued->frames[2].result_path.empty());
    RenderOne();
    EXPECT_EQ(farm_->scheduler().Get(*job)->state, JobState::kSucceeded);
    for (int f : {1, 2, 3}) ExpectFrame(*job, f);
}

}  // namespace
}  // namespace lf
