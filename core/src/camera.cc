#include "lf/core/camera.h"

#include <cmath>
#include <numbers>

#include "lf/core/disk_sampling.h"

namespace lf {

Camera::Camera(const CameraSpec& spec, const Vec3d& origin)
    : width_(spec.width), height_(spec.height), filter_(spec.filter) {
    const Vec3d f = Normalize(spec.look_at - spec.position);
    const Vec3d r = Normalize(Cross(f, spec.up));
    const Vec3d u = Cross(r, f);
    position_ = Vec3(spec.position - origin);
    forward_ = Vec3(f);
    right_ = Vec3(r);
    up_ = Vec3(u);
    tan_half_fov_ = float(std::tan(spec.fov_y_deg * std::numbers::pi / 360.0));
    aspect_ = float(width_) / float(height_);
    lens_radius_ = float(spec.aperture_radius);
    focus_distance_ = float(spec.focus_distance);
}

Ray Camera::GenerateRay(int px, int py, float u, float v, const Vec2& lens) const {
    const float x = (2 * (px + u) / width_ - 1) * tan_half_fov_ * aspect_;
    const float y = (1 - 2 * (py + v) / height_) * tan_half_fov_;
    const Vec3 through = forward_ + right_ * x + up_ * y;  // forward component 1
    if (lens_radius_ == 0) return Ray{position_, Normalize(through)};
    // Every ray through this film point meets the pinhole ray on the focal plane.
    const Vec3 focus = through * focus_distance_;
    const Vec2 d = SampleUniformDiskConcentric(lens);
    const Vec3 offset = right_ * (d.x * lens_radius_) + up_ * (d.y * lens_radius_);
    return Ray{position_ + offset, Normalize(focus - offset)};
}

}  // namespace lf
