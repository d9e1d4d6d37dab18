// A Draco-compressed glTF renders as its uncompressed twin (tests/scenes/draco, made by
// make_draco_twins.py): a textured sphere under a directional light, path traced with the same
// seed from both files.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "lf/core/scene_loader.h"
#include "render_path.h"

namespace lf {
namespace {

TEST(DracoRender, TheCompressedSphereRendersAsItsUncompressedTwin) {
    const std::string dir = std::string(LF_TEST_SCENES) + "/draco/";
    const SceneOptions options{.width = 48, .height = 48};
    const absl::StatusOr<Scene> plain = LoadScene(dir + "sphere.gltf", options);
    ASSERT_TRUE(plain.ok()) << plain.status();
    const absl::StatusOr<Scene> draco = LoadScene(dir + "sphere_draco.gltf", options);
    ASSERT_TRUE(draco.ok()) << draco.status();
    const Image a = testing::RenderPath(*plain, 16, -1, 7).out.image;
    const Image b = testing::RenderPath(*draco, 16, -1, 7).out.image;
    ASSERT_EQ(a.width(), b.width());
    double sum = 0, diff = 0, diff_squares = 0;
    const int n = a.width() * a.height();
    for (int y = 0; y < a.height(); ++y) {
        for (int x = 0; x < a.width(); ++x) {
            const Rgb pa = a.Pixel(x, y), pb = b.Pixel(x, y);
            const double la = (pa.r + pa.g + pa.b) / 3, lb = (pb.r + pb.g + pb.b) / 3;
            ASSERT_TRUE(std::isfinite(lb)) << x << " " << y;
            sum += la;
            diff += la - lb;
            diff_squares += (la - lb) * (la - lb);
        }
    }
    const double mean = sum / n, mean_diff = diff / n;
    const double standard_error =
        std::sqrt(std::max(0.0, diff_squares / n - mean_diff * mean_diff) / (n - 1));
    RecordProperty("mean", std::to_string(mean));
    RecordProperty("mean_difference", std::to_string(mean_diff));
    RecordProperty("standard_error", std::to_string(standard_error));
    EXPECT_GT(mean, 0.05);  // the sphere is in view and lit
    // Quantised normals (10 bits, about 2e-3 per component) change a cosine by under 1% where
    // the light is not grazing, and the uvs (12 bits) move a texel border by under a pixel's
    // width; beyond that the images differ by noise where the paths part.
    EXPECT_LE(std::abs(mean_diff), 0.01 * mean + 4 * standard_error)
        << "mean " << mean << " difference " << mean_diff << " standard error " << standard_error;
}

}  // namespace
}  // namespace lf
