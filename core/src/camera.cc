#include "lf/core/camera.h"

#include <cmath>
#include <numbers>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "lf/core/disk_sampling.h"

namespace lf {

namespace {

std::string Point(const Vec3d& p) { return absl::StrFormat("(%.6g, %.6g, %.6g)", p.x, p.y, p.z); }

}  // namespace

std::string DescribeCamera(const CameraSpec& spec) {
    const bool ortho = spec.projection == CameraSpec::Projection::kOrthographic;
    return absl::StrCat(
        ortho ? "orthographic" : "perspective", " from ", Point(spec.position), " towards ",
        Point(spec.look_at), ", up ", Point(spec.up),
        ortho ? absl::StrFormat(", half height %.6g", spec.half_height)
              : absl::StrFormat(", vertical field of view %.6g degrees", spec.fov_y_deg));
}

Camera::Camera(const CameraSpec& spec, const Vec3d& origin)
    : width_(spec.width), height_(spec.height), filter_spec_(spec.filter), filter_(spec.filter) {
    const Vec3d f = Normalize(spec.look_at - spec.position);
    const Vec3d r = Normalize(Cross(f, spec.up));
    const Vec3d u = Cross(r, f);
    position_ = Vec3(spec.position - origin);
    forward_ = Vec3(f);
    right_ = Vec3(r);
    up_ = Vec3(u);
    orthographic_ = spec.projection == CameraSpec::Projection::kOrthographic;
    tan_half_fov_ = orthographic_ ? float(spec.half_height)
                                  : float(std::tan(spec.fov_y_deg * std::numbers::pi / 360.0));
    aspect_ = float(width_) / float(height_);
    lens_radius_ = orthographic_ ? 0 : float(spec.aperture_radius);
    focus_distance_ = float(spec.focus_distance);
    film_area_ = 4 * tan_half_fov_ * tan_half_fov_ * aspect_;
    lens_area_ = lens_radius_ > 0 ? std::numbers::pi_v<float> * lens_radius_ * lens_radius_ : 1;
}

Ray Camera::GenerateRay(int px, int py, float u, float v, const Vec2& lens) const {
    const float x = (2 * (px + u) / width_ - 1) * tan_half_fov_ * aspect_;
    const float y = (1 - 2 * (py + v) / height_) * tan_half_fov_;
    if (orthographic_) return Ray{position_ + right_ * x + up_ * y, forward_};
    const Vec3 through = forward_ + right_ * x + up_ * y;  // forward component 1
    if (lens_radius_ == 0) return Ray{position_, Normalize(through)};
    // Every ray through this film point meets the pinhole ray on the focal plane.
    const Vec3 focus = through * focus_distance_;
    const Vec2 d = SampleUniformDiskConcentric(lens);
    const Vec3 offset = right_ * (d.x * lens_radius_) + up_ * (d.y * lens_radius_);
    return Ray{position_ + offset, Normalize(focus - offset)};
}

std::optional<Vec2> Camera::Raster(const Ray& ray, float* cos_theta) const {
    const float cos = Dot(ray.d, forward_);
    // A delta in direction: see IsOrthographic.
    if (orthographic_ || !(cos > 0)) return std::nullopt;
    // The film point at distance 1 along the view axis that GenerateRay would have aimed at: the
    // pinhole's own direction, or for a lens the pinhole ray through the point where this ray
    // crosses the focal plane.
    Vec3 through = ray.d / cos;
    if (lens_radius_ > 0) {
        const Vec3 focus = ray.o + ray.d * (focus_distance_ / cos);
        through = (focus - position_) / focus_distance_;
    }
    const float x = Dot(through, right_) / (tan_half_fov_ * aspect_);
    const float y = Dot(through, up_) / tan_half_fov_;
    const Vec2 raster{(x + 1) * 0.5f * width_, (1 - y) * 0.5f * height_};
    if (!(raster.x >= 0 && raster.x < width_ && raster.y >= 0 && raster.y < height_)) {
        return std::nullopt;
    }
    *cos_theta = cos;
    return raster;
}

float Camera::We(const Ray& ray, Vec2* raster) const {
    float cos = 0;
    const std::optional<Vec2> r = Raster(ray, &cos);
    if (!r) return 0;
    if (raster) *raster = *r;
    // Uniform over film area at distance 1 (dA = cos^3 dw there) and over the lens; one more
    // cosine for the lens's projected area.
    const float cos2 = cos * cos;
    return 1 / (film_area_ * lens_area_ * cos2 * cos2);
}

Camera::ImportancePdf Camera::PdfWe(const Ray& ray) const {
    float cos = 0;
    if (!Raster(ray, &cos)) return {};
    return {1 / lens_area_, 1 / (film_area_ * cos * cos * cos)};
}

std::optional<Camera::ImportanceSample> Camera::SampleWi(const Vec3& ref,
                                                         const Vec2& u_lens) const {
    ImportanceSample s;
    s.lens_point = position_;
    if (lens_radius_ > 0) {
        const Vec2 d = SampleUniformDiskConcentric(u_lens);
        s.lens_point += right_ * (d.x * lens_radius_) + up_ * (d.y * lens_radius_);
    }
    const Vec3 to_ref = ref - s.lens_point;
    s.distance = Length(to_ref);
    if (!(s.distance > 0)) return std::nullopt;
    const Ray ray{s.lens_point, to_ref / s.distance};
    s.we = We(ray, &s.raster);
    if (!(s.we > 0)) return std::nullopt;
    s.wi = -ray.d;
    s.pdf = s.distance * s.distance / (Dot(ray.d, forward_) * lens_area_);
    return s;
}

}  // namespace lf
