#include "lf/core/scene.h"

#include <limits>

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
    }
    return "unknown";
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
