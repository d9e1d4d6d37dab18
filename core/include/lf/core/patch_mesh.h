// Diffuse surfaces cut into patches for radiosity. Every scene triangle is subdivided
// barycentrically k x k into congruent sub-triangles whose corners are shared with their
// neighbours, so a hit (mesh, triangle, b1, b2) finds its patch by arithmetic and values can be
// interpolated at shared vertices.
//
// A patch has two sides. A side gets an unknown (a radiosity value to solve for) only if its
// radiosity can be non-zero: it is the front of an emitter, or its reflectance is not black and
// something (a vertex of another triangle or a point light) lies strictly in front of it.
// Every other side has radiosity exactly zero: in a closed box only the inward sides remain.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"

namespace lf {

struct PatchMeshOptions {
    double patch_size = 0;   // longest patch edge in scene units; 0: derived from `patches`
    int64_t patches = 4000;  // target patch count when patch_size is 0 (never exceeded unless
                             // the scene has more triangles)
};

// A triangle of the k x k subdivision grid of a scene triangle: its corners (i, j), each the
// point with barycentrics b1 = i/k, b2 = j/k, in the scene triangle's winding.
using GridTriangle = std::array<std::array<int32_t, 2>, 3>;

// The k^2 cells of the grid in patch order: row j = 0 .. k-1, along it alternately an upward
// cell (i, j), (i+1, j), (i, j+1) and a downward one (i+1, j), (i+1, j+1), (i, j+1).
std::vector<GridTriangle> SubdivisionCells(int k);

// A point of a patch: the patch and the point's barycentric weights on the patch's corners.
struct PatchPoint {
    int64_t patch = -1;
    std::array<double, 3> w{1, 0, 0};
};

class PatchMesh {
  public:
    struct Patch {
        int32_t mesh = 0;
        int32_t primitive = 0;                 // scene triangle
        std::array<uint32_t, 3> vertices{};    // indices into vertices(), same winding as the
                                               // scene triangle
        std::array<int32_t, 2> sides{-1, -1};  // unknown of the front / back side, or -1
        double area = 0;
        GridTriangle cell{};  // corners in the scene triangle's grid
    };
    struct Side {
        int32_t patch = 0;
        bool back = false;
    };

    // Fails for spheres and non-lambert materials, which radiosity does not model.
    static absl::StatusOr<PatchMesh> Build(const Scene& scene, const PatchMeshOptions& options);

    // The patch size used (derived from the target count if the options gave none).
    double patch_size() const { return patch_size_; }
    const std::vector<Vec3d>& vertices() const { return vertices_; }  // world space
    const std::vector<Patch>& patches() const { return patches_; }
    // Sorted by mesh, then front sides before back sides, then triangle and sub-triangle, so
    // runs of consecutive sides lie on one side of one surface.
    const std::vector<Side>& sides() const { return sides_; }

    int Subdivision(int mesh, int primitive) const { return triangle(mesh, primitive).k; }
    // Unit normal of the front face (that of the scene triangle).
    const Vec3d& Normal(int64_t patch) const;
    // Unit normal of a side: the front normal, flipped for a back side.
    Vec3d SideNormal(int32_t side) const;
    Vec3d Centroid(int64_t patch) const;

    // The patch containing barycentric point (b1, b2) of a scene triangle.
    PatchPoint Locate(int mesh, int primitive, double b1, double b2) const;
    // Barycentrics (b1, b2) in the scene triangle of the patch point with weights w.
    std::array<double, 2> TriangleBarycentrics(int64_t patch, const std::array<double, 3>& w) const;

  private:
    struct Triangle {
        int32_t k = 1;
        int64_t first_patch = 0;
        Vec3d normal;
    };

    const Triangle& triangle(int mesh, int primitive) const {
        return triangles_[size_t(mesh_first_triangle_[size_t(mesh)] + primitive)];
    }

    double patch_size_ = 0;
    std::vector<Vec3d> vertices_;
    std::vector<Patch> patches_;
    std::vector<Side> sides_;
    std::vector<Triangle> triangles_;
    std::vector<int64_t> mesh_first_triangle_;
};

}  // namespace lf
