#include "lf/core/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "absl/strings/str_cat.h"

namespace lf {

const char* MaterialTypeName(Material::Type type) {
    switch (type) {
        case Material::Type::kLambert:
            return "lambert";
        case Material::Type::kMirror:
            return "mirror";
        case Material::Type::kGlossy:
            return "glossy";
        case Material::Type::kDielectric:
            return "dielectric";
        case Material::Type::kPrincipled:
            return "principled";
        case Material::Type::kInterface:
            return "interface";
    }
    return "unknown";
}

bool Scene::HasMedia() const {
    if (!media.empty() || camera_medium >= 0) return true;
    return std::any_of(materials.begin(), materials.end(), [](const Material& m) {
        return m.type == Material::Type::kInterface;
    });
}

std::pair<Vec3d, Vec3d> Scene::Bounds() const {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    Vec3d lo(kInf, kInf, kInf), hi(-kInf, -kInf, -kInf);
    for (const TriangleMesh& mesh : meshes) {
        for (const Vec3d& p : mesh.positions) {
            lo = Min(lo, p);
            hi = Max(hi, p);
        }
    }
    for (const Sphere& s : spheres) {
        const Vec3d r(s.radius, s.radius, s.radius);
        lo = Min(lo, s.center - r);
        hi = Max(hi, s.center + r);
    }
    if (lo.x > hi.x) return {Vec3d(), Vec3d()};
    return {lo, hi};
}

namespace {

// False for NaN too, which a comparison of the largest component would let through.
bool WithinRange(const Vec3d& p) {
    return std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate &&
           std::abs(p.z) <= kMaxCoordinate;
}

// A direction the kernels take as unit: a transform that overflowed leaves it NaN or zero.
bool Unit(const Vec3d& v) { return std::abs(Length(v) - 1) < 1e-6; }

std::string Named(const std::string& name) { return name.empty() ? "" : " \"" + name + "\""; }

absl::Status Beyond(const std::string& what, const Vec3d& p) {
    return absl::InvalidArgumentError(absl::StrCat(what, " (", p.x, ", ", p.y, ", ", p.z,
                                                   ") is not finite and within ±", kMaxCoordinate));
}

}  // namespace

absl::Status CheckCoordinates(const Scene& scene) {
    const CameraSpec& c = scene.camera;
    if (!WithinRange(c.position)) return Beyond("camera position", c.position);
    if (!WithinRange(c.look_at)) return Beyond("camera look_at", c.look_at);
    if (!(Length(c.up) > 0 && std::isfinite(Length(c.up)))) return Beyond("camera up", c.up);
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const TriangleMesh& mesh = scene.meshes[m];
        for (size_t i = 0; i < mesh.positions.size(); ++i) {
            if (!WithinRange(mesh.positions[i])) {
                return Beyond(absl::StrCat("mesh ", m, Named(mesh.name), " vertex ", i),
                              mesh.positions[i]);
            }
        }
    }
    for (size_t i = 0; i < scene.spheres.size(); ++i) {
        const Sphere& s = scene.spheres[i];
        if (!WithinRange(s.center) || !(s.radius > 0 && s.radius <= kMaxCoordinate)) {
            return Beyond(
                absl::StrCat("sphere ", i, Named(s.name), " center (radius ", s.radius, ")"),
                s.center);
        }
    }
    for (size_t i = 0; i < scene.point_lights.size(); ++i) {
        if (!WithinRange(scene.point_lights[i].position)) {
            return Beyond(absl::StrCat("point light ", i, " position"),
                          scene.point_lights[i].position);
        }
    }
    for (size_t i = 0; i < scene.spot_lights.size(); ++i) {
        const SpotLight& l = scene.spot_lights[i];
        if (!WithinRange(l.position))
            return Beyond(absl::StrCat("spot light ", i, " position"), l.position);
        if (!Unit(l.direction))
            return Beyond(absl::StrCat("spot light ", i, " direction"), l.direction);
    }
    for (size_t i = 0; i < scene.directional_lights.size(); ++i) {
        const Vec3d& d = scene.directional_lights[i].direction;
        if (!Unit(d)) return Beyond(absl::StrCat("directional light ", i, " direction"), d);
    }
    return absl::OkStatus();
}

bool Scene::HasLights() const {
    if (!point_lights.empty() || !spot_lights.empty() || !directional_lights.empty() ||
        environment) {
        return true;
    }
    for (const TriangleMesh& mesh : meshes) {
        if (materials[size_t(mesh.material)].IsEmissive()) return true;
    }
    for (const Sphere& sphere : spheres) {
        if (materials[size_t(sphere.material)].IsEmissive()) return true;
    }
    return false;
}

}  // namespace lf
