// `--camera auto` (lf/core/auto_camera.h): the scene's bounding sphere fits the view.
#include "lf/core/auto_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lf/core/camera.h"

namespace lf {
namespace {

// A box from (1, 2, 3) to (5, 4, 4): every corner is inside the frame, and the sphere around
// the box touches the top and bottom of the frame (its tangent cone's half angle is fov/2).
TEST(FrameScene, TheBoundingSphereJustFitsTheFieldOfViewFromTheFrontAbove) {
    Scene scene;
    TriangleMesh mesh;
    mesh.positions = {{1, 2, 3}, {5, 4, 4}, {1, 4, 3}};
    mesh.triangles = {{0, 1, 2}};
    scene.meshes.push_back(mesh);
    const CameraSpec camera = FrameScene(scene);
    const Vec3d centre(3, 3, 3.5);
    const double radius = std::sqrt(16 + 4 + 1) / 2;
    EXPECT_NEAR(Length(camera.look_at - centre), 0, 1e-12);
    const Vec3d view = centre - camera.position;
    EXPECT_NEAR(radius / Length(view), std::sin(camera.fov_y_deg * std::numbers::pi / 360), 1e-12);
    // glTF's front: looking down -Z, from 20 degrees above.
    EXPECT_LT(view.z, 0);
    EXPECT_NEAR(std::atan2(-view.y, -view.z) * 180 / std::numbers::pi, 20, 1e-9);
    EXPECT_EQ(view.x, 0);
    const Camera cam(camera, Vec3d(0, 0, 0));
    for (int i = 0; i < 8; ++i) {
        const Vec3d corner(i & 1 ? 5 : 1, i & 2 ? 4 : 2, i & 4 ? 4 : 3);
        const Vec3d d = Normalize(corner - camera.position);
        EXPECT_GT(cam.We(Ray{Vec3(camera.position), Vec3(d)}), 0) << i;
    }
}

}  // namespace
}  // namespace lf
