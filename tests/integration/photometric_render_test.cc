// Photometric units end to end: a JSON scene's candela, loaded by ParseScene and rendered by the
// path tracer, give the radiance the closed form says.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lf/core/scene_loader.h"
#include "plane_render.h"
#include "render_path.h"

namespace lf {
namespace {

// A Lambertian plane of albedo 1 (testing::PlaneUnderCamera's plane) under a light 1 above the
// origin, seen from 3 above with a field of view of `fov_deg`: `light` is the rest of the
// light's JSON object.
std::string PlaneSceneJson(double fov_deg, const std::string& light) {
    return R"({"camera": {"position": [0, 3, 0], "look_at": [0, 0, 0], "up": [0, 0, 1],
                          "fov_y_deg": )" +
           std::to_string(fov_deg) + R"(, "resolution": [16, 16]},
               "materials": {"white": {"type": "lambert", "reflectance": [1, 1, 1]}},
               "shapes": [{"type": "quad", "material": "white",
                           "vertices": [[-50, 0, -50], [-50, 0, 50], [50, 0, 50], [50, 0, -50]]}],
               "lights": [{"type": "point", "position": [0, 1, 0], )" +
           light + "}]}";
}

// 683 cd of white is 1 W/sr per channel; at distance r and incidence angle theta the plane
// receives E = cos theta / r^2 and, with albedo 1, leaves L = E / pi: 1/pi under the light.
// The path tracer samples the point light exactly (a delta light: no sampling noise), so a
// pixel's spread comes only from where its samples fall in its footprint; ExpectPlaneMatches
// bounds it by 5 standard errors of the radiance's spread over the footprint.
// Returns the image.
Image ExpectPhotometricPlane(double fov_deg, const std::string& light) {
    const absl::StatusOr<Scene> scene =
        ParseScene(PlaneSceneJson(fov_deg, light), "plane.json", ReadBeside("."));
    EXPECT_TRUE(scene.ok()) << scene.status();
    if (!scene.ok()) return Image(1, 1);
    constexpr uint64_t kSpp = 16;
    const RenderOutput out = testing::RenderPath(*scene, kSpp).out;
    const auto radiance = [](const Vec3d& x) {
        const double r2 = x.x * x.x + x.z * x.z + 1;
        return Rgb(float(1 / std::sqrt(r2) / r2 / std::numbers::pi));
    };
    EXPECT_EQ(testing::ExpectPlaneMatches(*scene, out.image, kSpp, radiance),
              testing::kPlaneImageSize * testing::kPlaneImageSize);
    return out.image;
}

TEST(PhotometricRender, CandelaOverAPlaneGiveOneOverPiAtNormalIncidence) {
    // A 2 degree view sees |x|, |z| <= 3 tan 1 deg = 0.052 of the plane, where L = cos^3 / pi
    // is within 0.5% of 1/pi (cos^3 of atan(0.052 sqrt 2) = 0.996): every pixel is 1/pi to 1%,
    // which a missed factor of 683, pi or the luminance normalisation would be far outside.
    const Image image = ExpectPhotometricPlane(2, R"("intensity_cd": 683, "color": [1, 1, 1])");
    for (int y = 0; y < testing::kPlaneImageSize; ++y) {
        for (int x = 0; x < testing::kPlaneImageSize; ++x) {
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(image.Pixel(x, y)[c], 1 / std::numbers::pi, 0.01 / std::numbers::pi);
            }
        }
    }
}

TEST(PhotometricRender, LumensOfAPointLightSpreadOverTheSphere) {
    // 4 pi x 683 lm from a point light is 683 cd in every direction; the whole closed form over
    // a 60 degree view of the plane.
    ExpectPhotometricPlane(60, R"("power_lm": )" + std::to_string(4 * std::numbers::pi * 683));
}

}  // namespace
}  // namespace lf
