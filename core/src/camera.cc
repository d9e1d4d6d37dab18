#include "lf/core/camera.h"

#include <cmath>
#include <numbers>

namespace lf {

Camera::Camera(const CameraSpec& spec, const Vec3d& origin)
    : width_(spec.width), height_(spec.height) {
    const Vec3d f = Normalize(spec.look_at - spec.position);
    const Vec3d r = Normalize(Cross(f, spec.up));
    const Vec3d u = Cross(r, f);
    position_ = Vec3(spec.position - origin);
    forward_ = Vec3(f);
    right_ = Vec3(r);
    up_ = Vec3(u);
    tan_half_fov_ = float(std::tan(spec.fov_y_deg * std::numbers::pi / 360.0));
    aspect_ = float(width_) / float(height_);
}

Ray Camera::GenerateRay(int px, int py, float u, float v) const {
    const float x = (2 * (px + u) / width_ - 1) * tan_half_fov_ * aspect_;
    const float y = (1 - 2 * (py + v) / height_) * tan_half_fov_;
    return Ray{position_, Normalize(forward_ + right_ * x + up_ * y)};
}

}  // namespace lf
