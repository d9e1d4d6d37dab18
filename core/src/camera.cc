#include "lf/core/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "lf/core/disk_sampling.h"

namespace lf {

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

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

namespace {

struct Basis {
    Vec3d forward, right, up;
};

Basis BasisOf(const CameraSpec& spec) {
    const Vec3d f = Normalize(spec.look_at - spec.position);
    const Vec3d r = Normalize(Cross(f, spec.up));
    return {f, r, Cross(r, f)};
}

// The unit quaternion (x, y, z, w) of the rotation whose matrix has columns right, up,
// -forward (Shepperd's method: the largest of the four candidates keeps precision).
std::array<double, 4> QuaternionOf(const Basis& b) {
    const Vec3d c0 = b.right, c1 = b.up, c2 = -b.forward;
    const double m00 = c0.x, m11 = c1.y, m22 = c2.z, trace = m00 + m11 + m22;
    std::array<double, 4> q;
    if (trace > 0) {
        const double s = 2 * std::sqrt(1 + trace);
        q = {(c1.z - c2.y) / s, (c2.x - c0.z) / s, (c0.y - c1.x) / s, s / 4};
    } else if (m00 > m11 && m00 > m22) {
        const double s = 2 * std::sqrt(1 + m00 - m11 - m22);
        q = {s / 4, (c1.x + c0.y) / s, (c2.x + c0.z) / s, (c1.z - c2.y) / s};
    } else if (m11 > m22) {
        const double s = 2 * std::sqrt(1 + m11 - m00 - m22);
        q = {(c1.x + c0.y) / s, s / 4, (c2.y + c1.z) / s, (c2.x - c0.z) / s};
    } else {
        const double s = 2 * std::sqrt(1 + m22 - m00 - m11);
        q = {(c2.x + c0.z) / s, (c2.y + c1.z) / s, s / 4, (c0.y - c1.x) / s};
    }
    return q;
}

// q applied to v.
Vec3d Rotate(const std::array<double, 4>& q, const Vec3d& v) {
    const Vec3d u{q[0], q[1], q[2]};
    const Vec3d t = Cross(u, v) * 2.0;
    return v + t * q[3] + Cross(u, t);
}

// Along the shorter arc from a to b.
std::array<double, 4> Slerp(std::array<double, 4> a, const std::array<double, 4>& b, double t) {
    double cos = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    if (cos < 0) {
        for (double& c : a) c = -c;
        cos = -cos;
    }
    double wa = 1 - t, wb = t;
    if (cos < 0.9995) {  // else nearly parallel: linear, then normalised, is exact enough
        const double angle = std::acos(cos), sin = std::sin(angle);
        wa = std::sin((1 - t) * angle) / sin;
        wb = std::sin(t * angle) / sin;
    }
    std::array<double, 4> q;
    double norm = 0;
    for (int i = 0; i < 4; ++i) {
        q[size_t(i)] = wa * a[size_t(i)] + wb * b[size_t(i)];
        norm += q[size_t(i)] * q[size_t(i)];
    }
    for (double& c : q) c /= std::sqrt(norm);
    return q;
}

}  // namespace

Camera::Camera(const CameraSpec& spec, const Vec3d& origin, std::span<const CameraSpec> motion)
    : width_(spec.width), height_(spec.height), filter_spec_(spec.filter), filter_(spec.filter) {
    const Basis b = BasisOf(spec);
    pose_ = {Vec3(spec.position - origin), Vec3(b.forward), Vec3(b.right), Vec3(b.up)};
    for (const CameraSpec& step : motion) {
        motion_.push_back({step.position - origin, QuaternionOf(BasisOf(step))});
    }
    orthographic_ = spec.projection == CameraSpec::Projection::kOrthographic;
    tan_half_fov_ = orthographic_ ? float(spec.half_height)
                                  : float(std::tan(spec.fov_y_deg * std::numbers::pi / 360.0));
    aspect_ = float(width_) / float(height_);
    lens_radius_ = orthographic_ ? 0 : float(spec.aperture_radius);
    focus_distance_ = float(spec.focus_distance);
    film_area_ = 4 * tan_half_fov_ * tan_half_fov_ * aspect_;
    lens_area_ = lens_radius_ > 0 ? std::numbers::pi_v<float> * lens_radius_ * lens_radius_ : 1;
}

Camera::Pose Camera::PoseAt(float time) const {
    if (motion_.empty()) return pose_;
    const double x = std::clamp(double(time), 0.0, 1.0) * double(motion_.size() - 1);
    const size_t i = std::min(size_t(x), motion_.size() - 2);
    const double f = x - double(i);
    const MotionKey &a = motion_[i], &b = motion_[i + 1];
    const std::array<double, 4> q = Slerp(a.rotation, b.rotation, f);
    return {Vec3(a.position * (1 - f) + b.position * f), Vec3(Rotate(q, Vec3d{0, 0, -1})),
            Vec3(Rotate(q, Vec3d{1, 0, 0})), Vec3(Rotate(q, Vec3d{0, 1, 0}))};
}

Ray Camera::GenerateRay(int px, int py, float u, float v, const Vec2& lens, float time) const {
    const Pose pose = PoseAt(time);
    const float x = (2 * (px + u) / width_ - 1) * tan_half_fov_ * aspect_;
    const float y = (1 - 2 * (py + v) / height_) * tan_half_fov_;
    if (orthographic_) {
        return Ray{pose.position + pose.right * x + pose.up * y, pose.forward, kInfinity, time};
    }
    const Vec3 through = pose.forward + pose.right * x + pose.up * y;  // forward component 1
    if (lens_radius_ == 0) return Ray{pose.position, Normalize(through), kInfinity, time};
    // Every ray through this film point meets the pinhole ray on the focal plane.
    const Vec3 focus = through * focus_distance_;
    const Vec2 d = SampleUniformDiskConcentric(lens);
    const Vec3 offset = pose.right * (d.x * lens_radius_) + pose.up * (d.y * lens_radius_);
    return Ray{pose.position + offset, Normalize(focus - offset), kInfinity, time};
}

std::optional<Vec2> Camera::Raster(const Ray& ray, const Pose& pose, float* cos_theta) const {
    const float cos = Dot(ray.d, pose.forward);
    // A delta in direction: see IsOrthographic.
    if (orthographic_ || !(cos > 0)) return std::nullopt;
    // The film point at distance 1 along the view axis that GenerateRay would have aimed at: the
    // pinhole's own direction, or for a lens the pinhole ray through the point where this ray
    // crosses the focal plane.
    Vec3 through = ray.d / cos;
    if (lens_radius_ > 0) {
        const Vec3 focus = ray.o + ray.d * (focus_distance_ / cos);
        through = (focus - pose.position) / focus_distance_;
    }
    const float x = Dot(through, pose.right) / (tan_half_fov_ * aspect_);
    const float y = Dot(through, pose.up) / tan_half_fov_;
    const Vec2 raster{(x + 1) * 0.5f * width_, (1 - y) * 0.5f * height_};
    if (!(raster.x >= 0 && raster.x < width_ && raster.y >= 0 && raster.y < height_)) {
        return std::nullopt;
    }
    *cos_theta = cos;
    return raster;
}

float Camera::We(const Ray& ray, Vec2* raster) const {
    float cos = 0;
    const std::optional<Vec2> r = Raster(ray, PoseAt(ray.time), &cos);
    if (!r) return 0;
    if (raster) *raster = *r;
    // Uniform over film area at distance 1 (dA = cos^3 dw there) and over the lens; one more
    // cosine for the lens's projected area.
    const float cos2 = cos * cos;
    return 1 / (film_area_ * lens_area_ * cos2 * cos2);
}

Camera::ImportancePdf Camera::PdfWe(const Ray& ray) const {
    float cos = 0;
    if (!Raster(ray, PoseAt(ray.time), &cos)) return {};
    return {1 / lens_area_, 1 / (film_area_ * cos * cos * cos)};
}

std::optional<Camera::ImportanceSample> Camera::SampleWi(const Vec3& ref, const Vec2& u_lens,
                                                         float time) const {
    const Pose pose = PoseAt(time);
    ImportanceSample s;
    s.lens_point = pose.position;
    if (lens_radius_ > 0) {
        const Vec2 d = SampleUniformDiskConcentric(u_lens);
        s.lens_point += pose.right * (d.x * lens_radius_) + pose.up * (d.y * lens_radius_);
    }
    const Vec3 to_ref = ref - s.lens_point;
    s.distance = Length(to_ref);
    if (!(s.distance > 0)) return std::nullopt;
    const Ray ray{s.lens_point, to_ref / s.distance, kInfinity, time};
    s.we = We(ray, &s.raster);
    if (!(s.we > 0)) return std::nullopt;
    s.wi = -ray.d;
    s.pdf = s.distance * s.distance / (Dot(ray.d, pose.forward) * lens_area_);
    return s;
}

}  // namespace lf
