#include "lf/core/sphere_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "lf/core/scene_animation.h"

namespace lf {
namespace {

const Sphere kBall = {"ball", 2, Vec3d(1, -2, 3), 0.7, {true, 1, -1}};

TEST(SphereMesh, IsTheSphereWithinTheTolerance) {
    const int n = SphereMeshFrequency(kSphereMeshTolerance);
    EXPECT_EQ(n, 10);
    const TriangleMesh mesh = SphereMesh(kBall, n);
    EXPECT_EQ(mesh.triangles.size(), size_t(20 * n * n));
    // Shared vertices: a closed mesh of genus 0 has V = F / 2 + 2.
    EXPECT_EQ(mesh.positions.size(), mesh.triangles.size() / 2 + 2);
    EXPECT_EQ(mesh.name, "ball");
    EXPECT_EQ(mesh.material, 2);
    EXPECT_EQ(mesh.media.interior, 1);
    ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
    const double r = kBall.radius;
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const Vec3d d = mesh.positions[v] - kBall.center;
        EXPECT_NEAR(Length(d), r, 1e-12 * r);
        EXPECT_NEAR(Length(mesh.normals[v]), 1, 1e-6);
        EXPECT_NEAR(Dot(Vec3d(mesh.normals[v]), d / r), 1, 1e-6);  // radial
    }
    double area = 0;
    for (const auto& t : mesh.triangles) {
        const Vec3d& a = mesh.positions[t[0]];
        const Vec3d n2 = Cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a);
        // Outward: the front normal points away from the centre, and the triangle's plane lies
        // within the tolerance of the sphere.
        const Vec3d centroid =
            (a + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0 - kBall.center;
        EXPECT_GT(Dot(n2, centroid), 0);
        EXPECT_LE(r - Dot(Normalize(n2), a - kBall.center), kSphereMeshTolerance * r);
        area += Length(n2) / 2;
    }
    const double sphere_area = 4 * std::numbers::pi * r * r;
    EXPECT_LT(area, sphere_area);  // inscribed
    EXPECT_NEAR(area / sphere_area, 1, 0.005);
    std::printf("frequency %d: %zu triangles, area %.5f of 4 pi r^2\n", n, mesh.triangles.size(),
                area / sphere_area);
}

TEST(SphereMesh, FrequencyFollowsTheToleranceAndIsBounded) {
    EXPECT_EQ(SphereMeshFrequency(1), 1);
    EXPECT_LT(SphereMeshFrequency(1e-2), SphereMeshFrequency(1e-3));
    EXPECT_EQ(SphereMeshFrequency(0), kMaxSphereMeshFrequency);
}

TEST(SphereMesh, IsDeterministic) {
    const TriangleMesh a = SphereMesh(kBall, 7), b = SphereMesh(kBall, 7);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.triangles, b.triangles);
    ASSERT_EQ(a.normals.size(), b.normals.size());
    for (size_t v = 0; v < a.normals.size(); ++v) EXPECT_EQ(a.normals[v], b.normals[v]);
}

TEST(SphereMesh, TessellateSpheresAppendsMeshesAndMovesThemWithTheAnimation) {
    Scene scene;
    scene.materials.resize(3);
    scene.meshes.emplace_back().name = "floor";
    scene.spheres = {kBall, {"moon", 1, Vec3d(0, 5, 0), 2}};
    scene.content_hash = "input";
    auto animation = std::make_shared<SceneAnimation>();
    AnimationNode& node = animation->nodes.emplace_back();
    node.translation = Vec3d(10, 0, 0);
    animation->spheres.push_back({1, 0, Vec3d(0, 5, 0), 2, false});
    scene.animation = animation;

    TessellateSpheres(scene);
    EXPECT_TRUE(scene.spheres.empty());
    ASSERT_EQ(scene.meshes.size(), 3u);
    EXPECT_EQ(scene.meshes[1].name, "ball");
    EXPECT_EQ(scene.meshes[2].name, "moon");
    EXPECT_EQ(scene.content_hash, "input");
    ASSERT_TRUE(scene.animation);
    EXPECT_TRUE(scene.animation->spheres.empty());
    ASSERT_EQ(scene.animation->meshes.size(), 1u);
    EXPECT_EQ(scene.animation->meshes[0].mesh, 2);
    ASSERT_TRUE(scene.animation->PoseAt(0, scene).ok());
    // The node's translation moved the moon's mesh as it would have moved the sphere.
    for (const Vec3d& p : scene.meshes[2].positions) {
        EXPECT_NEAR(Length(p - Vec3d(10, 5, 0)), 2, 1e-9);
    }
}

}  // namespace
}  // namespace lf
