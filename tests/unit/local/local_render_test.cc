// Local mode without the CLI (lf/local/local_render.h): a render of a tiny scene gives the bits
// of RenderImage with the same kernel and settings, its header says how it was made, and the
// summary carries what the CLI prints.
#include "lf/local/local_render.h"

#include <gtest/gtest.h>

#include <string>

#include "lf/core/camera.h"
#include "lf/core/image_io.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "test_dir.h"

namespace lf {
namespace {

TEST(LocalRender, PathTracedImageIsRenderImagesBits) {
    const std::string exr = (testing::FreshTestDir("local_render") / "out.exr").string();
    LocalRenderOptions options;
    options.scene_path = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    options.scene.width = options.scene.height = 8;
    options.exr_path = exr;
    options.render.spp = 4;
    options.render.threads = 2;
    options.method = Method::kPath;
    absl::StatusOr<LocalRenderSummary> summary = RunLocalRender(options);
    ASSERT_TRUE(summary.ok()) << summary.status();
    EXPECT_EQ(summary->method, Method::kPath);
    EXPECT_EQ(summary->width, 8);
    EXPECT_EQ(summary->stats.samples, 8u * 8 * 4);

    absl::StatusOr<Scene> scene = LoadScene(options.scene_path, options.scene);
    ASSERT_TRUE(scene.ok()) << scene.status();
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    ASSERT_TRUE(embree.ok()) << embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    const PathTracer tracer(**embree, options.max_depth, options.render.light_strategy);
    absl::StatusOr<RenderOutput> direct = RenderImage(camera, tracer, options.render);
    ASSERT_TRUE(direct.ok()) << direct.status();

    absl::StatusOr<ExrFile> file = ReadExr(exr);
    ASSERT_TRUE(file.ok()) << file.status();
    for (const char* channel : {"R", "G", "B", "A.R", "B.R"}) {
        ASSERT_NE(file->image.FindChannel(channel), nullptr) << channel;
        EXPECT_EQ(*file->image.FindChannel(channel), *direct->image.FindChannel(channel))
            << channel;
    }
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.method")), "path");
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.sceneHash")),
              scene->content_hash);
    EXPECT_EQ(std::get<int>(file->attributes.at("lightfarm.spp")), 4);
}

// The splatting methods take the box filter only, refused before any sampling.
TEST(LocalRender, LightTracingRefusesOtherPixelFilters) {
    LocalRenderOptions options;
    options.scene_path = std::string(LF_TEST_SCENES) + "/cornell_box.json";
    options.scene.width = options.scene.height = 8;
    options.scene.filter = PixelFilter{PixelFilter::Type::kGaussian, 2};
    options.method = Method::kLight;
    absl::StatusOr<LocalRenderSummary> summary = RunLocalRender(options);
    ASSERT_FALSE(summary.ok());
    EXPECT_EQ(summary.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(summary.status().message().find("method light"), std::string::npos)
        << summary.status();
    EXPECT_NE(summary.status().message().find("gaussian"), std::string::npos) << summary.status();
}

}  // namespace
}  // namespace lf
