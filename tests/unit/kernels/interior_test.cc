// Paths through the interior of solid transmitters: Beer's law attenuation, per channel,
// sigma = -ln(attenuation_color) / attenuation_distance, as the homogeneous absorbing medium
// AddAttenuationMedia puts inside them.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "lf/core/camera.h"
#include "render_path.h"
#include "test_scenes.h"

namespace lf {
namespace {

// 5 standard errors: a correct renderer fails with probability below 1e-6 per check.
constexpr double kSigmas = 5.0;

// A cube of side 1 made of a material with IOR 1 (no refraction, no Fresnel reflection head
// on) in front of an emitter of radiance 1, seen head-on through a narrow camera: each pixel is
// exp(-sigma L / cos a) for the ray's angle a off the axis. The red channel is not attenuated,
// so the throughput's maximum stays 1 and roulette never fires: the answer is exact.
class Interior : public ::testing::TestWithParam<Material::Type> {};

TEST_P(Interior, TransmittedRadianceFollowsBeersLaw) {
    Scene scene;
    Material glass;
    glass.type = GetParam();
    glass.ior = 1;
    glass.reflectance = Rgb(1);  // the principled base colour tints each crossing: untinted here
    glass.attenuation_color = Rgb(1, 0.5f, 0.25f);
    glass.attenuation_distance = 0.5f;
    // The principled material is solid glass when it transmits and has a thickness (glTF's
    // KHR_materials_volume); smooth, not metallic.
    glass.transmission = 1;
    glass.thickness = 1;
    glass.roughness = 0;
    glass.metallic = 0;
    scene.materials.push_back(glass);
    testing::AddInwardBox(scene, Vec3d(), 0.5, 0);
    for (TriangleMesh& mesh : scene.meshes) {
        for (auto& t : mesh.triangles) std::swap(t[1], t[2]);  // outward: the outside is +n
    }
    Material emitter;
    emitter.reflectance = Rgb(0);
    emitter.emission = Rgb(1);
    scene.materials.push_back(emitter);
    TriangleMesh back;
    back.material = 1;
    back.positions = {{-5, 5, -2}, {-5, -5, -2}, {5, -5, -2}, {5, 5, -2}};
    back.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(back);
    scene.camera = testing::SquareCamera({0, 0, 10}, {0, 0, 0}, {0, 1, 0}, 2, 8);
    AddAttenuationMedia(scene);

    const RenderOutput out = testing::RenderPath(scene, 64).out;
    const Camera camera(scene.camera, Vec3d());
    // Beer's law over a path of length l: attenuation_color^(l / attenuation_distance).
    const auto beer = [&](double length, int c) {
        return std::pow(double(glass.attenuation_color[c]), length / glass.attenuation_distance);
    };
    // Each pixel over its own expectation (its ray angle): the mean of these ratios is 1. The
    // dielectric's transmission is a delta lobe with weight 1 (exact); the principled one
    // picks its lobes with a floor, so some paths end at a surface and the others carry the
    // weight up: noise, with the standard error from the pixels' spread.
    for (int c = 0; c < 3; ++c) {
        double sum = 0, sum2 = 0;
        const int n = scene.camera.width * scene.camera.height;
        for (int y = 0; y < scene.camera.height; ++y) {
            for (int x = 0; x < scene.camera.width; ++x) {
                const float cos_a = -camera.GenerateRay(x, y, 0.5f, 0.5f).d.z;
                // The footprint's spread of 1 / cos a is below 1e-5 at this field of view.
                const double ratio = out.image.Pixel(x, y)[c] / beer(1 / cos_a, c);
                sum += ratio;
                sum2 += ratio * ratio;
            }
        }
        const double mean = sum / n;
        const double standard_error = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
        EXPECT_LT(standard_error, 0.01) << "channel " << c;
        EXPECT_NEAR(mean, 1, kSigmas * standard_error + 1e-4) << "channel " << c;
    }
}

INSTANTIATE_TEST_SUITE_P(SolidTransmitters, Interior,
                         ::testing::Values(Material::Type::kPrincipled,
                                           Material::Type::kDielectric),
                         [](const auto& info) { return MaterialTypeName(info.param); });

}  // namespace
}  // namespace lf
