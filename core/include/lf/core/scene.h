// The scene model: what a scene file describes, validated and in double precision.
// Kernels convert it once into their own representation (Embree geometry, patches).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "lf/core/rgb.h"
#include "lf/core/vec.h"

namespace lf {

struct Material {
    enum class Type { kLambert, kMirror, kGlossy, kDielectric };
    enum class Distribution { kGgx, kBeckmann };

    std::string name;
    Type type = Type::kLambert;
    Rgb reflectance{0.8f};  // lambert albedo; mirror and glossy (dielectric-like) F0 tint
    Distribution distribution = Distribution::kGgx;
    float roughness = 0.1f;  // microfacet alpha
    bool conductor = false;  // glossy with complex IOR eta + i k instead of reflectance
    Rgb eta{1.0f}, k{0.0f};
    float ior = 1.5f;    // dielectric: interior IOR over exterior IOR
    Rgb emission{0.0f};  // radiance leaving the front face, W m^-2 sr^-1

    bool IsEmissive() const { return !emission.IsBlack(); }
};

const char* MaterialTypeName(Material::Type type);

// Quads, triangles and meshes all become triangle meshes. Front face normal of triangle
// (v0, v1, v2) is normalize((v1 - v0) x (v2 - v0)).
struct TriangleMesh {
    std::string name;
    int material = 0;
    std::vector<Vec3d> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    // True when the mesh came from a `quad` shape: (v0,v1,v2),(v0,v2,v3). Radiosity meshes
    // such shapes as a grid of quads rather than triangles.
    bool is_quad = false;
};

struct Sphere {
    std::string name;
    int material = 0;
    Vec3d center;
    double radius = 1;
};

struct PointLight {
    Vec3d position;
    Rgb intensity;  // W/sr per channel
};

struct CameraSpec {
    Vec3d position{0, 0, 0};
    Vec3d look_at{0, 0, 1};
    Vec3d up{0, 1, 0};
    double fov_y_deg = 45;
    int width = 256;
    int height = 256;
};

struct Scene {
    CameraSpec camera;
    std::vector<Material> materials;
    std::vector<TriangleMesh> meshes;
    std::vector<Sphere> spheres;
    std::vector<PointLight> point_lights;

    std::string source;        // path of the scene file, for messages
    std::string content_hash;  // hex digest of the scene file and every mesh file it names
    int dropped_degenerate = 0;

    // Axis-aligned bounds of all geometry.
    std::pair<Vec3d, Vec3d> Bounds() const;
    bool AllLambertian() const;
};

}  // namespace lf
