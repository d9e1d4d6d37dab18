// Paths through the interior of solid transmitters: Beer's law attenuation, per channel,
// sigma = -ln(attenuation_color) / attenuation_distance.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "lf/core/camera.h"
#include "lf/kernels/shading.h"
#include "render_path.h"
#include "test_scenes.h"

namespace lf {
namespace {

TEST(Transmittance, BeersLawPerChannel) {
    Material m;
    m.attenuation_color = Rgb(1, 0.5f, 0);
    m.attenuation_distance = 2;
    const Rgb t = Transmittance(m, 3);
    EXPECT_FLOAT_EQ(t.r, 1);
    EXPECT_FLOAT_EQ(t.g, std::exp(-(-std::log(0.5f) / 2) * 3));
    EXPECT_EQ(t.b, 0);
    EXPECT_EQ(Transmittance(m, 0), Rgb(1));  // no NaN from 0 * infinity
    m.attenuation_distance = std::numeric_limits<float>::infinity();
    EXPECT_EQ(Transmittance(m, 3), Rgb(1));
}

// A cube of side 1 made of a material with IOR 1 (no refraction, no Fresnel reflection) in
// front of an emitter of radiance 1, seen head-on through a narrow camera: each pixel is
// exp(-sigma L / cos a) for the ray's angle a off the axis. The red channel is not attenuated,
// so the throughput's maximum stays 1 and roulette never fires: the answer is exact.
TEST(Interior, TransmittedRadianceFollowsBeersLaw) {
    // The principled material (thickness > 0) shares this code path; its BSDF is not merged in
    // this branch, so the test uses the dielectric at IOR 1, which transmits everything.
    Scene scene;
    Material glass;
    glass.type = Material::Type::kDielectric;
    glass.ior = 1;
    glass.attenuation_color = Rgb(1, 0.5f, 0.25f);
    glass.attenuation_distance = 0.5f;
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
    scene.camera.position = {0, 0, 10};
    scene.camera.look_at = {0, 0, 0};
    scene.camera.fov_y_deg = 2;
    scene.camera.width = scene.camera.height = 8;

    const RenderOutput out = testing::RenderPath(scene, 4).out;
    const Camera camera(scene.camera, Vec3d());
    for (int y = 0; y < 8; ++y) {
        for (int x = 0; x < 8; ++x) {
            const float cos_a = -camera.GenerateRay(x, y, 0.5f, 0.5f).d.z;
            const Rgb expected = Transmittance(glass, 1 / cos_a);
            const Rgb got = out.image.Pixel(x, y);
            for (int c = 0; c < 3; ++c) {
                // The footprint's spread of 1 / cos a is below 1e-5 at this field of view.
                EXPECT_NEAR(got[c], expected[c], 1e-4) << "pixel " << x << "," << y << " ch " << c;
            }
            EXPECT_NEAR(got.g, 0.25f, 1e-3);  // exp(-ln(2) / 0.5 * 1) = 1/4 on the axis
        }
    }
}

}  // namespace
}  // namespace lf
