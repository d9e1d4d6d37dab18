// Radiosity of analytic spheres, which it meshes (lf/core/sphere_mesh.h) through the method's
// scene preparation (PrepareSceneFor), against closed forms: a convex sphere sees nothing of
// itself, so its radiosity is its albedo times the direct irradiance.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lf/job/method_registry.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/radiosity.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

// A lone diffuse sphere of albedo `albedo`, meshed as radiosity renders it.
Scene SphereScene(float albedo, const Vec3d& center, double radius) {
    Scene scene;
    Material m;
    m.name = "clay";
    m.reflectance = Rgb(albedo, albedo * 0.5f, albedo * 0.25f);
    scene.materials.push_back(m);
    scene.spheres.push_back({"ball", 0, center, radius});
    PrepareSceneFor(Method::kRadiosity, scene);
    return scene;
}

// The radiosity furnace with a sphere: under a uniform sky of radiance L every outward side
// receives pi L unoccluded (the sky's cosine-weighted estimate of a constant is exact), so its
// radiosity is rho pi L everywhere; the inward sides see only the sphere's dark inside.
TEST(RadiositySphere, UnderAUniformSkyItsRadiosityIsAlbedoTimesPiL) {
    Scene scene = SphereScene(0.6f, Vec3d(0.3, -0.2, 0.1), 0.5);
    ASSERT_TRUE(scene.spheres.empty());
    ASSERT_EQ(scene.meshes.size(), 1u);
    EnvironmentLight sky;
    sky.radiance = Rgb(2.0f);
    scene.environment = sky;
    auto embree = EmbreeScene::Build(scene);
    ASSERT_TRUE(embree.ok()) << embree.status();
    RadiosityOptions options;
    options.patches = 500;  // below the sphere's triangle count: one patch a triangle
    auto r = PrepareRadiosity(**embree, options);
    ASSERT_TRUE(r.ok()) << r.status();
    const PatchMesh& mesh = (*r)->mesh();
    EXPECT_EQ(mesh.patches().size(), scene.meshes[0].triangles.size());
    const Rgb expected = scene.materials[0].reflectance * float(kPi * 2.0);
    int outward = 0;
    for (size_t s = 0; s < mesh.sides().size(); ++s) {
        const Rgb& b = (*r)->radiosity()[s];
        if (mesh.sides()[s].back) {
            EXPECT_EQ(b.r, 0) << "side " << s;
            continue;
        }
        ++outward;
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(b[c], expected[c], 0.01 * expected[c]) << "side " << s << " channel " << c;
        }
    }
    EXPECT_EQ(outward, int(mesh.patches().size()));
}

// A point light of intensity I at distance d from the centre: the irradiance at the point
// nearest the light is I / (d - r)^2 (the patch's mean, within 1 % at the mesh's resolution).
TEST(RadiositySphere, PointLightGivesTheInverseSquareBelowIt) {
    const double r = 0.5, d = 3;
    const Vec3d center(0, 0, 0), light = Normalize(Vec3d(0.2, 0.8, 0.5)) * d;
    Scene scene = SphereScene(0.5f, center, r);
    const Rgb intensity(4, 5, 6);
    scene.point_lights.push_back({light, intensity});
    auto embree = EmbreeScene::Build(scene);
    ASSERT_TRUE(embree.ok()) << embree.status();
    RadiosityOptions options;
    options.patches = 500;
    options.display = RadiosityShading::kFlat;
    auto renderer = PrepareRadiosity(**embree, options);
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    const Vec3d toward = Normalize(center - light);
    const Ray ray{Vec3(light - (*embree)->origin()), Vec3(toward)};
    const auto hit = (*embree)->Intersect(ray);
    ASSERT_TRUE(hit);
    ASSERT_EQ(hit->mesh, 0);
    const Rgb got =
        (*renderer)->display().Irradiance(hit->mesh, hit->primitive, hit->b1, hit->b2, false);
    const double expected = 1 / ((d - r) * (d - r));
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(got[c], intensity[c] * expected, 0.01 * intensity[c] * expected)
            << "channel " << c;
    }
}

}  // namespace
}  // namespace lf
