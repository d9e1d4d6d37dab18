#include "lf/core/camera.h"

#include <gtest/gtest.h>

#include <numbers>

namespace lf {
namespace {

CameraSpec Spec() {
    CameraSpec s;
    s.position = {1, 2, 3};
    s.look_at = {1, 2, 10};
    s.up = {0, 1, 0};
    s.fov_y_deg = 60;
    s.width = 200;
    s.height = 100;
    return s;
}

TEST(Camera, CentreRayLooksAtTarget) {
    const Camera cam(Spec(), Vec3d(0, 0, 0));
    const Ray r = cam.GenerateRay(100, 50, 0.0f, 0.0f);  // exactly the image centre
    EXPECT_NEAR(r.d.x, 0, 1e-6);
    EXPECT_NEAR(r.d.y, 0, 1e-6);
    EXPECT_NEAR(r.d.z, 1, 1e-6);
    EXPECT_FLOAT_EQ(r.o.x, 1);
}

TEST(Camera, EdgesSpanTheFieldOfView) {
    const Camera cam(Spec(), Vec3d(0, 0, 0));
    // Top edge of the image: y = tan(fov/2), angle to the axis is fov/2 = 30 degrees.
    const Ray top = cam.GenerateRay(100, 0, 0.0f, 0.0f);
    EXPECT_NEAR(std::atan2(top.d.y, top.d.z) * 180 / std::numbers::pi, 30.0, 1e-4);
    // Right edge: x = tan(fov/2) * W/H; f x up = (0,0,1) x (0,1,0) = (-1,0,0) is "right".
    const Ray right = cam.GenerateRay(199, 50, 1.0f, 0.0f);
    EXPECT_NEAR(-right.d.x / right.d.z, std::tan(std::numbers::pi / 6) * 2, 1e-5);
}

TEST(Camera, OriginIsSubtracted) {
    const Camera cam(Spec(), Vec3d(1, 2, 3));
    const Ray r = cam.GenerateRay(0, 0, 0.5f, 0.5f);
    EXPECT_EQ(r.o, Vec3(0, 0, 0));
}

}  // namespace
}  // namespace lf
