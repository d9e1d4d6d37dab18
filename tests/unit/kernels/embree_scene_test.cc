// Ray casting against the Embree scene: hits, normals, and rays that leave a surface never
// hitting it again, at any distance from the origin.
#include "lf/kernels/embree_scene.h"

#include <gtest/gtest.h>

#include <random>

#include "test_scenes.h"

namespace lf {
namespace {

Scene SphereScene(const Vec3d& center, double radius) {
    Scene scene;
    scene.materials.push_back(Material{});
    scene.spheres.push_back({"s", 0, center, radius});
    return scene;
}

TEST(EmbreeScene, SphereHitFromOutsideAndInside) {
    const Scene scene = SphereScene(Vec3d(1, 2, 3), 0.5);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    const Vec3 c((*es)->SphereCenter(0, 0));
    auto outside = (*es)->Intersect(Ray{c + Vec3(0, 0, -2), Vec3(0, 0, 1)});
    ASSERT_TRUE(outside);
    EXPECT_NEAR(outside->t, 1.5f, 1e-5f);
    EXPECT_NEAR(outside->n.z, -1.0f, 1e-5f);  // outward normal
    EXPECT_EQ(outside->sphere, 0);
    auto inside = (*es)->Intersect(Ray{c, Vec3(1, 0, 0)});
    ASSERT_TRUE(inside);
    EXPECT_NEAR(inside->t, 0.5f, 1e-5f);
    EXPECT_NEAR(inside->n.x, 1.0f, 1e-5f);
}

// A worker's cancel reaches Embree's BVH build through its progress monitor.
TEST(EmbreeScene, BuildStopsOnceCancelled) {
    const Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 4);
    std::atomic<bool> cancel{true};
    const auto cancelled = EmbreeScene::Build(scene, &cancel);
    EXPECT_TRUE(absl::IsCancelled(cancelled.status())) << cancelled.status();
    cancel = false;
    const auto built = EmbreeScene::Build(scene, &cancel);
    EXPECT_TRUE(built.ok()) << built.status();
}

TEST(EmbreeScene, TriangleHitReportsFrontNormalAndBarycentrics) {
    Scene scene = testing::MakeFurnace(1.0, Vec3d(), 0.5f, 1.0f, 4);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    auto hit = (*es)->Intersect(Ray{Vec3(0.2f, 0.3f, 0), Vec3(0, -1, 0)});
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->t, 1.3f, 1e-5f);
    EXPECT_NEAR(hit->n.y, 1.0f, 1e-6f);  // the floor faces into the box
    const SurfacePoint sp = (*es)->TrianglePoint(hit->mesh, hit->primitive, hit->b1, hit->b2, 0);
    EXPECT_NEAR(sp.p.x, 0.2f, 1e-5f);
    EXPECT_NEAR(sp.p.z, 0.0f, 1e-5f);
}

// From random points on the walls of a box 10^5 from the origin (and of a box 10^5 wide),
// rays spawned into the box must never hit the wall they start on, and shadow rays between two
// points that see each other must never be blocked.
class SpawnedRays : public ::testing::TestWithParam<std::pair<double, double>> {};

TEST_P(SpawnedRays, NeverReHitTheirOwnSurface) {
    const auto [half, offset] = GetParam();
    Scene scene = testing::MakeFurnace(half, Vec3d(offset, -offset, offset), 0.5f, 1.0f, 4);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int self_hits = 0, blocked = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        // A random point seen from the box centre, then a random direction into the box.
        const Vec3 d = Normalize(Vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f));
        auto first = (*es)->Intersect(Ray{Vec3(0, 0, 0), d});
        ASSERT_TRUE(first);
        const SurfacePoint a{first->p, first->p_error, first->n};
        const Frame frame = Frame::FromNormal(first->n);
        const float z = std::max(1e-4f, u(rng)), phi = 6.2831853f * u(rng);
        const float r = std::sqrt(std::max(0.0f, 1 - z * z));
        const Vec3 w = frame.FromLocal(Vec3(r * std::cos(phi), r * std::sin(phi), z));
        auto second = (*es)->Intersect(SpawnRay(a, w));
        ASSERT_TRUE(second);  // a closed box: every ray hits a wall
        if (second->mesh == first->mesh && second->primitive == first->primitive) ++self_hits;
        const SurfacePoint b{second->p, second->p_error, second->n};
        if ((*es)->Occluded(SpawnRayTo(a, b))) ++blocked;
    }
    EXPECT_EQ(self_hits, 0);
    EXPECT_EQ(blocked, 0);
}

INSTANTIATE_TEST_SUITE_P(Scales, SpawnedRays,
                         ::testing::Values(std::pair{1.0, 0.0}, std::pair{1e-4, 0.0},
                                           std::pair{1e5, 0.0}, std::pair{1.0, 1e5},
                                           std::pair{1e3, 1e5}));

}  // namespace
}  // namespace lf
