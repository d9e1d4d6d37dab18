#include "lf/core/auto_camera.h"

#include <cmath>
#include <numbers>

namespace lf {

CameraSpec FrameScene(const Scene& scene) {
    constexpr double kFovDeg = 40, kElevationDeg = 20;
    const auto [lo, hi] = scene.Bounds();
    const Vec3d centre = (lo + hi) * 0.5;
    double radius = Length(hi - lo) * 0.5;
    if (!(radius > 0)) radius = 1;  // a point or nothing: any view will do
    const double elevation = kElevationDeg * std::numbers::pi / 180;
    const double distance = radius / std::sin(kFovDeg * std::numbers::pi / 360);
    CameraSpec camera;
    camera.look_at = centre;
    camera.position = centre + Vec3d(0, std::sin(elevation), std::cos(elevation)) * distance;
    camera.up = {0, 1, 0};
    camera.fov_y_deg = kFovDeg;
    camera.width = 1024;
    camera.height = 768;
    return camera;
}

}  // namespace lf
