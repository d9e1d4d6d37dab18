#include "lf/core/camera.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

// Where a ray meets the plane z = z0 (the camera looks along +z from z = 3).
Vec3 AtDepth(const Ray& r, float z0) { return r.o + r.d * ((z0 - r.o.z) / r.d.z); }

// Thin lens: every ray through one film point, whatever lens point it leaves from, passes through
// the same point of the focal plane (that point stays sharp), and that point is where the pinhole
// ray through the film point goes.
TEST(Camera, ThinLensFocusesEveryLensPointOnTheFocalPlane) {
    CameraSpec spec = Spec();
    spec.aperture_radius = 0.2;
    spec.focus_distance = 4;
    const Camera lens(spec, Vec3d(0, 0, 0));
    const Camera pinhole(Spec(), Vec3d(0, 0, 0));
    ASSERT_TRUE(lens.HasLens());
    ASSERT_FALSE(pinhole.HasLens());
    const Vec3 sharp = AtDepth(pinhole.GenerateRay(37, 81, 0.25f, 0.5f), 3 + 4);
    for (const Vec2 u :
         {Vec2{0.1f, 0.9f}, Vec2{0.5f, 0.5f}, Vec2{0.99f, 0.01f}, Vec2{0.3f, 0.6f}}) {
        const Ray r = lens.GenerateRay(37, 81, 0.25f, 0.5f, u);
        const Vec3 p = AtDepth(r, 3 + 4);
        EXPECT_NEAR(p.x, sharp.x, 1e-5);
        EXPECT_NEAR(p.y, sharp.y, 1e-5);
        // The ray leaves from the lens disk, in the plane through the camera across the view.
        EXPECT_NEAR(r.o.z, 3, 1e-6);
        EXPECT_LE(std::hypot(r.o.x - 1, r.o.y - 2), 0.2f + 1e-6f);
    }
}

// Off the focal plane, the rays through the image centre from the whole lens cover a disk: the
// circle of confusion, of diameter 2 R |z - f| / f at distance z (similar triangles).
TEST(Camera, ThinLensBlurCircleHasTheThinLensDiameter) {
    CameraSpec spec = Spec();
    spec.aperture_radius = 0.1;
    spec.focus_distance = 5;
    const Camera lens(spec, Vec3d(0, 0, 0));
    for (const double z : {2.0, 8.0, 20.0}) {
        float widest = 0;
        constexpr int kGrid = 64;
        for (int i = 0; i < kGrid; ++i) {
            for (int j = 0; j < kGrid; ++j) {
                const Vec2 u{(i + 0.5f) / kGrid, (j + 0.5f) / kGrid};
                const Vec3 p = AtDepth(lens.GenerateRay(100, 50, 0.0f, 0.0f, u), float(3 + z));
                widest = std::max(widest, 2 * std::hypot(p.x - 1, p.y - 2));
            }
        }
        const double expected = 2 * 0.1 * std::abs(z - 5) / 5;
        // The grid's outermost samples sit half a cell inside the rim.
        EXPECT_NEAR(widest, expected, expected * 2.0 / kGrid + 1e-5) << z;
    }
}

// Orthographic (glTF xmag/ymag): a point's pixel is its offset from the view axis over the film's
// half extents, x = <p - o, r> / (h W/H), y = <p - o, u'> / h, raster ((x + 1) W/2, (1 - y) H/2);
// the ray through that raster position runs parallel to the view axis through the point, from
// the film plane, whatever the point's depth.
TEST(Camera, OrthographicRayThroughAPointsClosedFormPixelMeetsIt) {
    CameraSpec spec = Spec();
    spec.projection = CameraSpec::Projection::kOrthographic;
    spec.half_height = 2;        // half width 4 at 200 x 100
    spec.aperture_radius = 0.5;  // no meaning for an orthographic camera: ignored
    const Camera cam(spec, Vec3d(0, 0, 0));
    EXPECT_TRUE(cam.IsOrthographic());
    EXPECT_FALSE(cam.HasLens());
    // right = f x up = (-1, 0, 0), up' = (0, 1, 0), from (1, 2, 3).
    for (const Vec3d p : {Vec3d(2, 3, 7), Vec3d(-2.5, 0.5, 40), Vec3d(4.9, 3.9, 3.5)}) {
        const double x = -(p.x - 1) / 4, y = (p.y - 2) / 2;
        const double rx = (x + 1) * 100, ry = (1 - y) * 50;
        const int px = int(std::floor(rx)), py = int(std::floor(ry));
        const Ray r = cam.GenerateRay(px, py, float(rx - px), float(ry - py));
        EXPECT_NEAR(r.d.x, 0, 1e-7);
        EXPECT_NEAR(r.d.y, 0, 1e-7);
        EXPECT_NEAR(r.d.z, 1, 1e-7);
        EXPECT_NEAR(r.o.z, 3, 1e-6);
        EXPECT_NEAR(r.o.x, p.x, 1e-5) << p.x;
        EXPECT_NEAR(r.o.y, p.y, 1e-5) << p.y;
    }
    // Light paths cannot reach it by chance: no importance.
    EXPECT_FALSE(cam.SampleWi(Vec3(2, 3, 7)).has_value());
    EXPECT_EQ(cam.We(Ray{Vec3(2, 3, 3), Vec3(0, 0, 1)}), 0);
}

// The render log's camera line: enough to set up the same view in another renderer.
TEST(Camera, DescribesItsViewInOneLine) {
    EXPECT_EQ(DescribeCamera(Spec()),
              "perspective from (1, 2, 3) towards (1, 2, 10), up (0, 1, 0), vertical field of "
              "view 60 degrees");
    CameraSpec ortho = Spec();
    ortho.projection = CameraSpec::Projection::kOrthographic;
    ortho.half_height = 0.25;
    ortho.position = {0.5, -1e-7, 1234567};
    EXPECT_EQ(DescribeCamera(ortho),
              "orthographic from (0.5, -1e-07, 1.23457e+06) towards (1, 2, 10), up (0, 1, 0), "
              "half height 0.25");
}

// A moving camera (motion blur): at time t it is between its two nearest poses, its position
// linear and its orientation slerped, so a camera panning a quarter turn looks 45 degrees
// round at the middle of the shutter; the ray carries its time.
TEST(Camera, AMovingCameraIsBetweenItsPosesAtTheRaysTime) {
    CameraSpec open = Spec(), close = Spec();
    close.position = {3, 2, 3};
    close.look_at = {10, 2, 3};  // from +z to +x: a quarter turn about +y
    const CameraSpec motion[] = {open, close};
    const Camera cam(Spec(), Vec3d(0, 0, 0), motion);
    EXPECT_TRUE(cam.Moves());
    for (const float t : {0.0f, 0.25f, 0.5f, 1.0f}) {
        const Ray r = cam.GenerateRay(100, 50, 0.0f, 0.0f, {}, t);
        const double angle = t * std::numbers::pi / 2;
        EXPECT_NEAR(r.d.x, std::sin(angle), 1e-5) << t;
        EXPECT_NEAR(r.d.z, std::cos(angle), 1e-5) << t;
        EXPECT_NEAR(r.d.y, 0, 1e-5) << t;
        EXPECT_NEAR(r.o.x, 1 + 2 * t, 1e-5) << t;
        EXPECT_EQ(r.time, t);
        // The importance of that ray finds it at the film's centre at the same time only.
        Vec2 raster;
        ASSERT_GT(cam.We(r, &raster), 0) << t;
        EXPECT_NEAR(raster.x, 100, 1e-2) << t;
        EXPECT_NEAR(raster.y, 50, 1e-2) << t;
    }
    EXPECT_FALSE(Camera(Spec(), Vec3d(0, 0, 0)).Moves());
}

}  // namespace
}  // namespace lf
