// glTF scenes rendered: the same pixels as the equivalent JSON scene, and `lightfarm render`
// with --camera and --resolution on a glTF file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "gltf_files.h"
#include "image_files.h"
#include "lf/core/image_io.h"
#include "lf/core/scene_loader.h"
#include "lightfarm_process.h"
#include "render_path.h"
#include "test_dir.h"
#include "test_scenes.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class GltfRender : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = testing::FreshTestDir("lf_gltf_render");
        const testing::GltfBuilder b = testing::TexturedTestScene();
        Write("scene.gltf", b.Gltf("scene.bin"));
        Write("scene.bin", b.bin());
        Write("tex.png", testing::PngBytes(2, 2, 4, testing::TestTexels()));
        Write("scene.json", testing::TexturedTestSceneJson());
        Write("quad.obj", testing::TexturedTestQuadObj());
    }
    void TearDown() override { fs::remove_all(dir_); }

    void Write(const std::string& name, const std::string& bytes) {
        std::ofstream(dir_ / name, std::ios::binary) << bytes;
    }

    // `lightfarm ARGS` with stdout and stderr.
    std::pair<int, std::string> Lightfarm(const std::string& args) {
        testing::LightfarmRun run = testing::RunLightfarm(args);
        return {run.status, std::move(run.output)};
    }

    fs::path dir_;
};

// The glTF's nodes, transforms, camera, point light, principled materials, texture and vertex
// normals against the same scene written by hand in JSON (the textured quad an OBJ with vt and
// vn), through the path tracer with one seed. Vertex positions agree to rounding (the glTF's
// come through a quaternion), so the images agree within their noise and almost every pixel is
// the same bits.
TEST_F(GltfRender, RendersTheSamePixelsAsTheEquivalentJsonScene) {
    const SceneOptions small{.camera = "", .width = 48, .height = 32};
    absl::StatusOr<Scene> gltf = LoadScene((dir_ / "scene.gltf").string(), small);
    absl::StatusOr<Scene> json = LoadScene((dir_ / "scene.json").string(), small);
    ASSERT_TRUE(gltf.ok()) << gltf.status();
    ASSERT_TRUE(json.ok()) << json.status();
    // The file's camera sees the textured quad small and at a slant; this one fills the image
    // with it, so a texture read the wrong way up changes most pixels.
    for (Scene* scene : {&*gltf, &*json}) {
        scene->camera.position = {3.5, 1, -1};
        scene->camera.look_at = {1, 1, -1};
        scene->camera.fov_y_deg = 50;
    }
    ASSERT_EQ(gltf->meshes.size(), json->meshes.size());
    for (size_t m = 0; m < json->meshes.size(); ++m) {
        EXPECT_EQ(gltf->meshes[m].normals.size(), json->meshes[m].normals.size()) << m;
        EXPECT_EQ(gltf->meshes[m].uvs.size(), json->meshes[m].uvs.size()) << m;
    }
    const testing::PathRender a = testing::RenderPath(*gltf, 64, 4, 7);
    const testing::PathRender b = testing::RenderPath(*json, 64, 4, 7);
    for (const char* channel : {"R", "G", "B"}) {
        const testing::MeanAndError ma = testing::ChannelMean(a.out.image, channel);
        const testing::MeanAndError mb = testing::ChannelMean(b.out.image, channel);
        EXPECT_GT(mb.mean, 0) << channel;  // lit: the comparison means something
        EXPECT_NEAR(ma.mean, mb.mean,
                    5 * std::hypot(ma.standard_error, mb.standard_error) + 1e-6 * mb.mean)
            << channel;
    }
    // Same sample sequence, same hits: almost every pixel is the same bits.
    size_t same = 0, total = 0;
    for (const char* channel : {"R", "G", "B"}) {
        const std::vector<float>& ca = *a.out.image.FindChannel(channel);
        const std::vector<float>& cb = *b.out.image.FindChannel(channel);
        for (size_t i = 0; i < ca.size(); ++i) same += ca[i] == cb[i];
        total += ca.size();
    }
    EXPECT_GT(double(same), 0.95 * double(total));
}

TEST_F(GltfRender, RenderCommandTakesGltfCameraAndResolution) {
    const std::string exr = (dir_ / "out.exr").string();
    const auto [status, out] = Lightfarm("render " + (dir_ / "scene.gltf").string() + " -o " + exr +
                                         " --spp 2 --camera Front --resolution 40x20 "
                                         "--no-progress");
    ASSERT_EQ(status, 0) << out;
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(file->image.width(), 40);
    EXPECT_EQ(file->image.height(), 20);

    const auto [bad_status, bad_out] =
        Lightfarm("render " + (dir_ / "scene.gltf").string() + " -o " + exr + " --camera Top");
    EXPECT_NE(bad_status, 0);
    EXPECT_NE(bad_out.find("scene.gltf: no camera named \"Top\"; the cameras are \"Front\""),
              std::string::npos)
        << bad_out;
    // A bare N is N x N, as for bench and converge.
    const auto [square_status, square_out] =
        Lightfarm("render " + (dir_ / "scene.gltf").string() + " -o " + exr +
                  " --spp 2 --camera Front --resolution 24 --no-progress");
    ASSERT_EQ(square_status, 0) << square_out;
    absl::StatusOr<ExrFile> square = ReadExr(exr);
    ASSERT_TRUE(square.ok()) << square.status();
    EXPECT_EQ(square->image.width(), 24);
    EXPECT_EQ(square->image.height(), 24);
    const auto [size_status, size_out] =
        Lightfarm("render " + (dir_ / "scene.gltf").string() + " -o " + exr + " --resolution 40y");
    EXPECT_NE(size_status, 0);
    EXPECT_NE(size_out.find("--resolution \"40y\": expected WxH, e.g. 1920x1080, or N for N x N"),
              std::string::npos)
        << size_out;
}

// A camera at 1e308 hit Embree's `ray.valid()` assertion: render died of SIGABRT (rc 134). The
// loader refuses it, so render fails with the message and the ordinary exit code.
TEST_F(GltfRender, RenderRefusesACameraBeyondTheCoordinateBoundInsteadOfAborting) {
    testing::GltfBuilder b = testing::TexturedTestScene();
    b.json()["nodes"][3]["translation"] = {1e308, 1, 6};  // "Front"
    Write("far.gltf", b.Gltf("far.bin"));
    Write("far.bin", b.bin());
    const auto [status, out] = Lightfarm("render " + (dir_ / "far.gltf").string() + " -o " +
                                         (dir_ / "far.exr").string() + " --spp 1 --no-progress");
    EXPECT_EQ(status, 1) << out;
    EXPECT_NE(
        out.find(
            "far.gltf: nodes[3] \"Front\": its world translation (1e+308, 1, 6) is beyond ±1e+15"),
        std::string::npos)
        << out;
    EXPECT_FALSE(fs::exists(dir_ / "far.exr"));
}

// Khronos' Cameras asset (CC0) through its orthographic camera, under a sun along the view
// axis: the square (x, y in [0, 1], turned 45 degrees about x) covers cos 45 of a unit square of
// the 2 x 2 film, so 17.7% of the pixels. The perspective camera (yfov 0.7, 3 away) sees it as
// a trapezoid: near edge y = -0.5 / (3 tan 0.35), half width 0.5 / (3 tan 0.35); far edge at
// depth 3 + cos 45, y = (sin 45 - 0.5) / depth, half width 0.5 / depth: 12.6% of the film.
TEST(GltfCamerasAsset, RendersWithEitherCamera) {
    const std::string path = std::string(LF_TEST_SCENES) + "/khronos/Cameras/Cameras.gltf";
    double covered[2] = {0, 0};
    for (int camera = 0; camera < 2; ++camera) {
        const SceneOptions options{.camera = std::to_string(camera), .width = 64, .height = 64};
        absl::StatusOr<Scene> scene = LoadScene(path, options);
        ASSERT_TRUE(scene.ok()) << scene.status();
        scene->directional_lights.push_back({Vec3d(0, 0, -1), Rgb(1.0f)});
        const testing::PathRender render = testing::RenderPath(*scene, 4, 2, 1);
        const std::vector<float>& r = *render.out.image.FindChannel("R");
        for (const float v : r) {
            ASSERT_TRUE(std::isfinite(v));
            covered[camera] += v > 0;
        }
        covered[camera] /= double(r.size());
    }
    // A pixel on the square's rim may be partly covered: 2 * (32 + 23) rim pixels of 4096.
    EXPECT_NEAR(covered[1], std::sqrt(0.5) / 4, 110.0 / 4096);
    const double t = std::tan(0.35), near = 3 * t, far = (3 + std::sqrt(0.5)) * t;
    const double trapezoid = (1 / near + 1 / far) / 2 * ((std::sqrt(0.5) - 0.5) / far + 0.5 / near);
    EXPECT_NEAR(covered[0], trapezoid / 4, 100.0 / 4096);
}

}  // namespace
}  // namespace lf
