// `render --frames` (RunLocalShot and the CLI): a ball moving at a known speed sits where the
// camera model projects it at each frame's time, a scene that does not move gives the still's
// bits every frame, and bad input fails before anything is written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "lf/core/camera.h"
#include "lf/core/image_io.h"
#include "lf/core/scene_animation.h"
#include "lf/core/scene_loader.h"
#include "lf/local/local_render.h"
#include "lightfarm_process.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

// tests/scenes/shots/make_shots.py's numbers: the ball's centre and the camera move linearly
// over 0..1 s.
constexpr Vec3d kBallFrom{-1.5, -0.5, 0}, kBallTo{1.5, 0.5, 0};
constexpr Vec3d kCameraFrom{0, 0, 5}, kCameraTo{0.5, 0.3, 5};
constexpr int kWidth = 64, kHeight = 48;

std::string Shots(const std::string& name) {
    return std::string(LF_TEST_SCENES) + "/shots/" + name;
}

Vec3d Lerp(const Vec3d& a, const Vec3d& b, double t) { return a + (b - a) * t; }

class ShotRender : public ::testing::Test {
  protected:
    void SetUp() override { dir_ = testing::FreshTestDir("lf_shot"); }
    void TearDown() override { fs::remove_all(dir_); }
    std::string Path(const std::string& name) const { return (dir_ / name).string(); }
    LocalRenderOptions Options(const std::string& scene, int spp) const {
        LocalRenderOptions o;
        o.scene_path = scene;
        o.scene.width = kWidth;
        o.scene.height = kHeight;
        o.render.spp = spp;
        return o;
    }
    size_t Files() const { return size_t(std::distance(fs::directory_iterator(dir_), {})); }
    fs::path dir_;
};

// The radiance-weighted mean raster position (x from the left, y from the top, in pixels).
Vec2 Centroid(const Image& image) {
    const std::vector<float>& r = *image.FindChannel("R");
    double sum = 0, sx = 0, sy = 0;
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            const double v = r[size_t(y) * size_t(image.width()) + size_t(x)];
            sum += v;
            sx += v * (x + 0.5);
            sy += v * (y + 0.5);
        }
    }
    return {float(sx / sum), float(sy / sum)};
}

// An emissive ball seen by a pinhole images as a uniform ellipse whose centroid is the
// projection of the ball's centre, off by f tan(angle off axis) (r / d)^2 at most: 0.07 pixels
// here. Pixel filters are symmetric and keep the centroid; the noise is the silhouette's
// coverage at 64 spp, a few hundredths of a pixel.
void ExpectBallWhereTheCameraProjectsIt(const std::string& scene_file, bool camera_moves,
                                        const std::string& dir) {
    SceneOptions scene_options;
    scene_options.width = kWidth;
    scene_options.height = kHeight;
    absl::StatusOr<Scene> rest = LoadScene(scene_file, scene_options);
    ASSERT_TRUE(rest.ok()) << rest.status();
    ASSERT_TRUE(rest->animation && rest->animation->Moves());

    LocalRenderOptions o;
    o.scene_path = scene_file;
    o.scene = scene_options;
    o.render.spp = 64;
    o.exr_path = dir + "/ball_####.exr";
    ShotSettings shot;
    shot.frames = FrameRange{1, 24, 1};
    absl::StatusOr<LocalShotSummary> summary = RunLocalShot(o, shot);
    ASSERT_TRUE(summary.ok()) << summary.status();
    ASSERT_EQ(summary->frames.size(), 24u);
    EXPECT_TRUE(summary->moves);
    for (int frame : {1, 12, 24}) {
        SCOPED_TRACE(frame);
        const double t = frame / 24.0;
        // The rest pose's camera, moved by the analytic translation of its node.
        CameraSpec spec = rest->camera;
        const Vec3d shift =
            camera_moves ? Lerp(kCameraFrom, kCameraTo, t) - kCameraFrom : Vec3d{0, 0, 0};
        spec.position = spec.position + shift;
        spec.look_at = spec.look_at + shift;
        const Camera camera(spec, Vec3d{0, 0, 0});
        const Vec3d ball = Lerp(kBallFrom, kBallTo, t);
        const std::optional<Camera::ImportanceSample> at =
            camera.SampleWi(Vec3(float(ball.x), float(ball.y), float(ball.z)));
        ASSERT_TRUE(at.has_value());

        absl::StatusOr<ExrFile> exr = ReadExr(summary->frames[size_t(frame - 1)].exr_path);
        ASSERT_TRUE(exr.ok()) << exr.status();
        EXPECT_EQ(std::get<int>(exr->attributes.at("lightfarm.frame")), frame);
        EXPECT_DOUBLE_EQ(std::get<double>(exr->attributes.at("lightfarm.time")), t);
        const Vec2 centroid = Centroid(exr->image);
        EXPECT_NEAR(centroid.x, at->raster.x, 0.5);
        EXPECT_NEAR(centroid.y, at->raster.y, 0.5);
    }
}

TEST_F(ShotRender, AMovingBallSitsWhereTheCameraProjectsIt) {
    ExpectBallWhereTheCameraProjectsIt(Shots("moving_ball.gltf"), false, dir_.string());
}

TEST_F(ShotRender, AMovingBallSitsWhereAMovingCameraProjectsIt) {
    ExpectBallWhereTheCameraProjectsIt(Shots("moving_ball_camera.gltf"), true, dir_.string());
}

TEST_F(ShotRender, AStaticSceneGivesTheStillsPixelsEveryFrame) {
    LocalRenderOptions still = Options(std::string(LF_TEST_SCENES) + "/cornell_box.json", 4);
    still.exr_path = Path("still.exr");
    ASSERT_TRUE(RunLocalRender(still).ok());
    LocalRenderOptions frames = still;
    frames.exr_path = Path("frame_##.exr");
    ShotSettings shot;
    shot.frames = FrameRange{1, 3, 1};
    absl::StatusOr<LocalShotSummary> summary = RunLocalShot(frames, shot);
    ASSERT_TRUE(summary.ok()) << summary.status();
    EXPECT_FALSE(summary->moves);
    absl::StatusOr<ExrFile> want = ReadExr(Path("still.exr"));
    ASSERT_TRUE(want.ok()) << want.status();
    for (const char* name : {"frame_01.exr", "frame_02.exr", "frame_03.exr"}) {
        SCOPED_TRACE(name);
        absl::StatusOr<ExrFile> got = ReadExr(Path(name));
        ASSERT_TRUE(got.ok()) << got.status();
        EXPECT_EQ(got->image.channels(), want->image.channels());
        EXPECT_EQ(want->attributes.count("lightfarm.frame"), 0u);
        EXPECT_TRUE(got->attributes.count("lightfarm.frame"));
    }
}

// Ctrl-C (asked before the first frame samples): that frame is written partial, none after it.
TEST_F(ShotRender, AnInterruptWritesTheFramePartialAndEndsTheShot) {
    LocalRenderOptions o = Options(Shots("moving_ball.gltf"), 4);
    o.exr_path = Path("i_#.exr");
    RenderInterrupt interrupt;
    interrupt.requested = true;
    o.interrupt = &interrupt;
    ShotSettings shot;
    shot.frames = FrameRange{1, 3, 1};
    absl::StatusOr<LocalShotSummary> summary = RunLocalShot(o, shot);
    ASSERT_TRUE(summary.ok()) << summary.status();
    ASSERT_EQ(summary->frames.size(), 1u);
    EXPECT_NE(summary->partial.find("frame 1 interrupted"), std::string::npos) << summary->partial;
    EXPECT_NE(summary->partial.find("1 frame of 3"), std::string::npos) << summary->partial;
    absl::StatusOr<ExrFile> exr = ReadExr(Path("i_1.exr"));
    ASSERT_TRUE(exr.ok()) << exr.status();
    EXPECT_TRUE(exr->attributes.count("lightfarm.partial"));
    EXPECT_EQ(Files(), 1u);
}

using testing::RunLightfarm;

TEST_F(ShotRender, BadFramesFailNamingWhatAndWriteNothing) {
    const std::string ball = Shots("moving_ball.gltf");
    const std::string small = " --resolution 16x12 --spp 1 --no-progress ";
    struct Case {
        std::string args, expected;
    } cases[] = {
        {"--frames 5-1 -o " + Path("a_#.exr"), "--frames: frames \"5-1\""},
        {"--frames '' -o " + Path("a_#.exr"), "the range is empty"},
        {"--frames 1-3 -o " + Path("a.exr"), "-o"},
        {"--frames 1-3 -o " + Path("a_#.exr") + " --png " + Path("a.png"), "--png"},
        {"--frame 2 --frames 1-3 -o " + Path("a_#.exr"), "--frame 2 with --frames 1-3"},
        {"--fps 0 --frames 1-3 -o " + Path("a_#.exr"), "--fps 0"},
        {"--fps 30 -o " + Path("a.exr"), "--fps 30"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.args);
        const testing::LightfarmRun run = RunLightfarm("render " + ball + small + c.args);
        EXPECT_NE(run.status, 0);
        EXPECT_NE(run.output.find(c.expected), std::string::npos) << run.output;
        EXPECT_EQ(Files(), 0u);
    }
}

TEST_F(ShotRender, AMalformedAnimationRefusesFramesNamingTheFile) {
    // The ball's translation channel samples an accessor of the wrong type (SCALAR).
    nlohmann::json gltf = nlohmann::json::parse(std::ifstream(Shots("moving_ball.gltf")));
    const int output = gltf["animations"][0]["samplers"][0]["output"];
    gltf["accessors"][output]["type"] = "SCALAR";
    const std::string scene = Path("broken.gltf");
    std::ofstream(scene) << gltf.dump();
    const testing::LightfarmRun run = RunLightfarm(
        "render " + scene + " --resolution 16x12 --spp 1 --no-progress --frames 1-3 -o " +
        Path("b_#.exr"));
    EXPECT_NE(run.status, 0);
    EXPECT_NE(run.output.find("broken.gltf"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("animations[0]"), std::string::npos) << run.output;
    EXPECT_EQ(Files(), 1u);  // the scene alone
}

// Image sum, and its standard error when each pixel averages `spp` samples of 0 or `peak` (a
// directly seen emitter on black: a pixel's variance is v (peak - v) / spp for its mean v;
// stratified samples only do better, so the bound is conservative).
struct ImageSum {
    double sum = 0, variance = 0;
};
ImageSum SumOf(const Image& image, uint64_t spp) {
    const std::vector<float>& r = *image.FindChannel("R");
    const double peak = *std::max_element(r.begin(), r.end());
    ImageSum s;
    for (float v : r) {
        s.sum += v;
        s.variance += std::max(0.0, double(v) * (peak - v)) / double(spp);
    }
    return s;
}

// `--shutter 1` on the ball moving at constant speed: the streak's centroid is the still's at the
// frame's time (the shutter is centred on it), and the light it sends is the still's (the
// emitter's brightness is conserved), each within its noise.
// The ball as a mesh (glTF) and as an analytic sphere (JSON): both blur about the frame's place.
TEST_F(ShotRender, AShutterCentredOnTheFrameKeepsTheBallsCentroidAndBrightness) {
    constexpr uint64_t kSpp = 256;
    for (const std::string scene : {"moving_ball.gltf", "moving_ball.json"}) {
        SCOPED_TRACE(scene);
        Image images[2];
        for (int blur = 0; blur < 2; ++blur) {
            LocalRenderOptions o = Options(Shots(scene), kSpp);
            o.exr_path = Path(scene + (blur ? "_blur_#.exr" : "_still_#.exr"));
            ShotSettings shot;
            shot.frames = FrameRange{12, 12, 1};
            shot.shutter = blur ? 1.0 : 0.0;
            absl::StatusOr<LocalShotSummary> summary = RunLocalShot(o, shot);
            ASSERT_TRUE(summary.ok()) << summary.status();
            absl::StatusOr<ExrFile> exr = ReadExr(summary->frames.at(0).exr_path);
            ASSERT_TRUE(exr.ok()) << exr.status();
            EXPECT_DOUBLE_EQ(std::get<double>(exr->attributes.at("lightfarm.shutter")),
                             shot.shutter);
            images[blur] = std::move(exr->image);
        }
        EXPECT_NE(*images[0].FindChannel("R"), *images[1].FindChannel("R"));  // it did blur
        const Vec2 still = Centroid(images[0]), blurred = Centroid(images[1]);
        EXPECT_NEAR(blurred.x, still.x, 0.25);
        EXPECT_NEAR(blurred.y, still.y, 0.25);
        const ImageSum a = SumOf(images[0], kSpp), b = SumOf(images[1], kSpp);
        EXPECT_NEAR(b.sum, a.sum, 4 * std::sqrt(a.variance + b.variance))
            << "still " << a.sum << ", blurred " << b.sum;
    }
}

// Nothing moves in the Cornell box: an open shutter changes no bit.
TEST_F(ShotRender, AStaticSceneRendersTheSameBitsWithAndWithoutAShutter) {
    std::vector<float> pixels[2];
    for (int blur = 0; blur < 2; ++blur) {
        LocalRenderOptions o = Options(std::string(LF_TEST_SCENES) + "/cornell_box.json", 4);
        o.exr_path = Path(blur ? "blur.exr" : "still.exr");
        ShotSettings shot;
        shot.frames = FrameRange{3, 3, 1};
        shot.shutter = blur ? 1.0 : 0.0;
        ASSERT_TRUE(RunLocalShot(o, shot).ok());
        absl::StatusOr<ExrFile> exr = ReadExr(o.exr_path);
        ASSERT_TRUE(exr.ok()) << exr.status();
        pixels[blur] = *exr->image.FindChannel("R");
    }
    EXPECT_EQ(pixels[0], pixels[1]);
}

TEST_F(ShotRender, AShutterWithoutFramesOrByRadiosityIsRefused) {
    const std::string small = " --resolution 16x12 --spp 1 --no-progress ";
    struct Case {
        std::string args, expected;
    } cases[] = {
        {"render " + Shots("moving_ball.gltf") + small + "--shutter 0.5 -o " + Path("a.exr"),
         "--shutter 0.5: motion blur needs --frames or --frame"},
        {"render " + Shots("moving_ball.gltf") + small + "--frame 2 --shutter 11 -o " +
             Path("a.exr"),
         "shutter 11"},
        {"render " + std::string(LF_TEST_SCENES) + "/cornell_box.json" + small +
             "--method radiosity --frame 2 --shutter 0.5 -o " + Path("a.exr"),
         "method \"radiosity\" solves one instant per frame"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.args);
        const testing::LightfarmRun run = RunLightfarm(c.args);
        EXPECT_NE(run.status, 0);
        EXPECT_NE(run.output.find(c.expected), std::string::npos) << run.output;
        EXPECT_EQ(Files(), 0u);
    }
}

// moving_ball.json's ball is an analytic sphere, which the shutter's steps do not move yet.
// A ball whose node also grows: its radius would change in the shutter, which is refused.
TEST_F(ShotRender, AShutterOverAGrowingAnalyticSphereIsRefusedNamingIt) {
    nlohmann::json scene = nlohmann::json::parse(std::ifstream(Shots("moving_ball.json")));
    scene["shapes"][0]["transform"]["keyframes"][0]["scale"] = 1;
    scene["shapes"][0]["transform"]["keyframes"][1]["scale"] = 2;
    const std::string file = Path("growing.json");
    std::ofstream(file) << scene.dump();
    const testing::LightfarmRun run = RunLightfarm(
        "render " + file + " --resolution 16x12 --spp 1 --no-progress --frame 12 --shutter 1 -o " +
        Path("s.exr"));
    EXPECT_NE(run.status, 0);
    EXPECT_NE(run.output.find("spheres[0]"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("changes size during the shutter"), std::string::npos) << run.output;
    EXPECT_EQ(Files(), 1u);  // the scene alone
}

// A Cornell box whose tall block slides: radiosity solves each frame anew, so one solution file
// cannot serve the shot.
TEST_F(ShotRender, RadiositySolutionFilesAreRefusedForAMovingShot) {
    nlohmann::json scene =
        nlohmann::json::parse(std::ifstream(std::string(LF_TEST_SCENES) + "/cornell_box.json"));
    scene["shapes"].back()["transform"] = {
        {"keyframes",
         {{{"time", 0}, {"translate", {0, 0, 0}}}, {{"time", 1}, {"translate", {0.05, 0, 0}}}}}};
    const std::string file = Path("sliding.json");
    std::ofstream(file) << scene.dump();
    std::ofstream(Path("solution.bin")) << "a solution";  // --load-solution wants a file
    for (const char* flag : {"--save-solution", "--load-solution", "--export-ply"}) {
        SCOPED_TRACE(flag);
        const testing::LightfarmRun run = RunLightfarm(
            "render " + file + " --method radiosity --resolution 16x12 --spp 1 --no-progress " +
            "--frames 1-2 -o " + Path("r_#.exr") + " " + flag + " " + Path("solution.bin"));
        EXPECT_NE(run.status, 0);
        EXPECT_NE(run.output.find(std::string(flag) + " "), std::string::npos) << run.output;
        EXPECT_NE(run.output.find("each frame solves anew"), std::string::npos) << run.output;
        EXPECT_EQ(Files(), 2u);  // the scene and the solution alone
    }
}

}  // namespace
}  // namespace lf