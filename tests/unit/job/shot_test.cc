#include "lf/job/shot.h"

#include <gtest/gtest.h>

#include "lf/core/scene.h"
#include "lf/job/job_spec.h"
#include "lf/job/render_metadata.h"

namespace lf {
namespace {

TEST(FrameRangeTest, ParsesRangesStepsSingleFramesAndNegatives) {
    struct Case {
        const char* text;
        FrameRange range;
        int count;
    };
    for (const Case& c : {Case{"1-24", {1, 24, 1}, 24}, Case{"1-24:2", {1, 24, 2}, 12},
                          Case{"12", {12, 12, 1}, 1}, Case{"-10--1", {-10, -1, 1}, 10},
                          Case{"-3-3:3", {-3, 3, 3}, 3}, Case{"0-239", {0, 239, 1}, 240}}) {
        absl::StatusOr<FrameRange> r = ParseFrameRange(c.text);
        ASSERT_TRUE(r.ok()) << c.text << ": " << r.status();
        EXPECT_EQ(*r, c.range) << c.text;
        EXPECT_EQ(r->count(), c.count) << c.text;
        EXPECT_EQ(FrameRangeText(*r), c.text);
    }
    const FrameRange r{1, 24, 2};
    EXPECT_EQ(r.at(11), 23);
    EXPECT_TRUE(r.Contains(23));
    EXPECT_FALSE(r.Contains(24));
    EXPECT_FALSE(r.Contains(25));
    EXPECT_EQ(r.IndexOf(23), 11);
}

TEST(FrameRangeTest, EmptyReversedAndMalformedRangesAreErrorsNamingThem) {
    struct Case {
        const char* text;
        const char* says;
    };
    for (const Case& c :
         {Case{"", "empty"}, Case{"24-1", "reversed"}, Case{"1-24:0", "step 0 is below 1"},
          Case{"1-24:-2", "below 1"}, Case{"1-", "expected FIRST-LAST"},
          Case{"a-b", "expected FIRST-LAST"}, Case{"1-24x", "expected FIRST-LAST"},
          Case{"1:2", "expected FIRST-LAST"}, Case{"0-2000000", "beyond"},
          Case{"1-20001", "more than 10000 frames"}, Case{"99999999999", "expected FIRST"}}) {
        absl::StatusOr<FrameRange> r = ParseFrameRange(c.text);
        ASSERT_FALSE(r.ok()) << c.text;
        EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(r.status().message().find(c.says), std::string_view::npos) << r.status();
        EXPECT_NE(r.status().message().find(std::string("\"") + c.text + "\""),
                  std::string_view::npos)
            << r.status();
    }
}

TEST(FramePathTest, HashesBecomeTheZeroPaddedFrameNumber) {
    EXPECT_EQ(FramePath("out_####.exr", 7), "out_0007.exr");
    EXPECT_EQ(FramePath("out_#.exr", 123), "out_123.exr");
    EXPECT_EQ(FramePath("f##/x.png", 5), "f05/x.png");
    EXPECT_EQ(FramePath("out_####.exr", -12), "out_-0012.exr");
    EXPECT_EQ(FramePath("still.exr", 3), "still.exr");
}

TEST(FramePathTest, APatternMustNumberEveryFrame) {
    EXPECT_TRUE(CheckFramePattern("-o", "out_####.exr", {1, 24, 1}).ok());
    EXPECT_TRUE(CheckFramePattern("-o", "still.exr", {5, 5, 1}).ok());
    absl::Status none = CheckFramePattern("-o", "out.exr", {1, 24, 1});
    EXPECT_EQ(none.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(none.message().find("-o \"out.exr\" has no '#'"), std::string_view::npos) << none;
    EXPECT_NE(none.message().find("24 frames (1-24)"), std::string_view::npos) << none;
    absl::Status two = CheckFramePattern("--png", "a##_##.png", {1, 2, 1});
    EXPECT_NE(two.message().find("more than one run"), std::string_view::npos) << two;
}

TEST(ShotSettingsTest, ShutterIsCentredOnTheFramesTime) {
    ShotSettings shot;
    shot.fps = 24;
    shot.shutter = 0.5;
    const ShutterInterval s = ShutterOf(12, shot);
    EXPECT_DOUBLE_EQ(s.open, 11.75 / 24);
    EXPECT_DOUBLE_EQ(s.close, 12.25 / 24);
    shot.shutter = 0;
    EXPECT_EQ(ShutterOf(12, shot).open, ShutterOf(12, shot).close);
    EXPECT_DOUBLE_EQ(FrameSeconds(12, 24), 0.5);
}

TEST(ShotSettingsTest, OutOfRangeSettingsAreRefusedNamingTheField) {
    struct Case {
        ShotSettings shot;
        const char* says;
    };
    const FrameRange frames{1, 2, 1};
    for (const Case& c :
         {Case{{frames, 0.0, 0, 1}, "fps 0"}, Case{{frames, std::nan(""), 0, 1}, "fps nan"},
          Case{{frames, 1e-310, 0, 1}, "expected 0.001 to 1000"},
          Case{{frames, 24, -1, 1}, "shutter -1"}, Case{{frames, 24, 11, 1}, "shutter 11"},
          Case{{frames, 24, 0, 0}, "chunk 0"},
          Case{{std::nullopt, 24, 0.5, 1}, "motion blur needs a frame"},
          Case{{FrameRange{3, 1, 1}, 24, 0, 1}, "reversed"}}) {
        absl::Status s = CheckShotSettings(c.shot);
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << c.says;
        EXPECT_NE(s.message().find(c.says), std::string_view::npos) << s;
    }
    EXPECT_TRUE(CheckShotSettings({frames, 24, 0.5, 8}).ok());
}

TEST(ShotSettingsTest, JobSettingsCheckTheShotAndRadiosityRefusesTheShutter) {
    JobSpec spec;
    spec.shot.frames = FrameRange{1, 24, 1};
    spec.shot.chunk = 0;
    EXPECT_NE(CheckJobSettings(spec).message().find("chunk 0"), std::string_view::npos);
    spec.shot.chunk = 2;
    spec.shot.shutter = 0.5;
    EXPECT_TRUE(CheckJobSettings(spec).ok()) << CheckJobSettings(spec);
    spec.method = "radiosity";
    const absl::Status s = CheckJobSettings(spec);
    EXPECT_NE(s.message().find("shutter: method \"radiosity\""), std::string_view::npos) << s;
}

TEST(ShotSettingsTest, AFramesHeaderNamesItsFrameTimeAndShutter) {
    JobSpec shot;
    shot.shot.frames = FrameRange{1, 24, 1};
    shot.shot.fps = 25;
    shot.shot.shutter = 0.5;
    shot.shot.chunk = 4;
    const JobSpec frame = FrameSpec(shot, 10);
    EXPECT_EQ(frame.shot.frames, (FrameRange{10, 10, 1}));
    EXPECT_EQ(frame.shot.chunk, 1);
    const RenderMetadata m = MetadataOf(frame, {});
    ASSERT_TRUE(m.frame.has_value());
    EXPECT_EQ(*m.frame, 10);
    Image image(2, 2);
    absl::StatusOr<RenderDescription> d = DescribeRender(m, image, false);
    ASSERT_TRUE(d.ok()) << d.status();
    EXPECT_EQ(std::get<int>(d->attributes.at("lightfarm.frame")), 10);
    EXPECT_DOUBLE_EQ(std::get<double>(d->attributes.at("lightfarm.time")), 0.4);
    EXPECT_DOUBLE_EQ(std::get<double>(d->attributes.at("lightfarm.fps")), 25);
    EXPECT_DOUBLE_EQ(std::get<double>(d->attributes.at("lightfarm.shutter")), 0.5);
    // A still's header has none of them.
    absl::StatusOr<RenderDescription> still =
        DescribeRender(MetadataOf(JobSpec{}, {}), image, false);
    ASSERT_TRUE(still.ok());
    EXPECT_FALSE(still->attributes.contains("lightfarm.frame"));
}

TEST(PoseSceneAtFrameTest, AStaticSceneStaysAndMalformedAnimationNamesTheFrame) {
    Scene scene;
    scene.source = "shot.json";
    scene.spheres.push_back({});
    ShotSettings shot;
    EXPECT_TRUE(PoseSceneAtFrame(12, shot, scene).ok());
    scene.animation_error = absl::InvalidArgumentError("animations[0].channels[1]: no node 9");
    const absl::Status s = PoseSceneAtFrame(12, shot, scene);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(s.message(), "frame 12 (0.5 s) of shot.json: animations[0].channels[1]: no node 9");
}

}  // namespace
}  // namespace lf
