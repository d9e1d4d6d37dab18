// Diffuse surfaces cut into patches for radiosity. Every scene triangle is subdivided
// barycentrically k x k into congruent sub-triangles whose corners are shared with their
// neighbours, so a hit (mesh, triangle, b1, b2) finds its patch by arithmetic and values can be
// interpolated at shared vertices.
//
// Refinement is local: any cell can be split 2 x 2 into congruent quarters (at the midpoints of
// its edges), and the quarters again, so a cell of level l is a cell of the grid with k 2^l
// divisions. A hit finds its coarse cell by arithmetic, then descends through the splits.
// Where a split cell meets an unsplit one, the midpoint is a vertex of the finer side only (a
// T-junction: the patches still tile the triangle, as Embree intersects the scene triangles).
//
// A patch has two sides. A side gets an unknown (a radiosity and an irradiance to solve for)
// only if either can be non-zero: it is the front of an emitter (either side of a two-sided one),
// or something (a vertex of another triangle, a light that can shine on it) lies strictly in
// front of it, whatever its reflectance (a black floor's illuminance is shown too).
// Every other side receives and sends nothing: in a closed box only the inward sides remain.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"

namespace lf {

// Why radiosity cannot model `scene` ("material \"leaf\" (mesh \"tree\") has an alpha mask,
// which radiosity does not model"), or empty when it can: radiosity solves for one radiosity per
// patch side, so it takes double-sided, opaque triangle meshes (no medium interfaces), and
// spheres as meshes (lf/core/sphere_mesh.h). What it approximates instead of refusing,
// RadiosityDrops says. Only materials some mesh or sphere uses count.
// `--method auto` logs it when it picks the path tracer.
std::string RadiosityLimitation(const Scene& scene);

// What radiosity leaves out of a scene it takes, by kind, naming the materials ("specular
// reflection: \"plastic\", \"floor\"; clear coat: \"car\""), or empty when nothing: it keeps
// every material's diffuse part (docs/radiosity.md, Scenes from modelling tools), so mirrors,
// glass and glossy metal render black, and speculars, transmission, coats, sheen and normal
// maps are dropped.
std::string RadiosityDrops(const Scene& scene);

// Whether a material's diffuse part can reflect anything whatever its textures.
bool MayReflectDiffusely(const Material& material);

// RadiosityLimitation as the error radiosity refuses a scene with (meshing, the solver, the
// farm's submission), or OK.
absl::Status RadiosityRefusal(const Scene& scene);

// A cell of a scene triangle's subdivision: upward (i, j), (i+1, j), (i, j+1) or downward
// (i+1, j), (i+1, j+1), (i, j+1) in the grid with k 2^level divisions.
struct PatchCell {
    int32_t mesh = 0, primitive = 0;
    int32_t level = 0;
    int32_t i = 0, j = 0;
    bool up = true;
    auto operator<=>(const PatchCell&) const = default;
};

// Splits nest at most this deep (4096 times finer than the coarse grid): far below any useful
// patch size, and grid coordinates k 2^level stay in 32 bits for every k the count limit allows.
inline constexpr int kMaxPatchLevel = 12;

// The most patches mesh refinement may reach (RadiosityOptions::max_patches): form factors take
// ~4 bytes per pair of sides, so 32k patches are about 3 GiB (and the previous pass's, held
// while the last pass's are computed, nearly as much again).
inline constexpr int64_t kMaxRefinedPatches = 32768;

struct PatchMeshOptions {
    double patch_size = 0;   // longest patch edge in scene units; 0: derived from `patches`
    int64_t patches = 4000;  // target patch count when patch_size is 0 (never exceeded unless
                             // the scene has more triangles)
    // Cells split into quarters; a cell of level l > 0 must be a quarter of a split cell. Any
    // order, duplicates allowed.
    std::vector<PatchCell> split = {};
    // Set from another thread: Build returns Cancelled within a row of one triangle's grid.
    const std::atomic<bool>* cancel = nullptr;
};

// A triangle of a subdivision grid of a scene triangle: its corners (i, j), each the point with
// barycentrics b1 = i/K, b2 = j/K (K = k 2^level), in the scene triangle's winding.
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
        GridTriangle cell{};  // corners in the scene triangle's grid of level `level`
        int32_t level = 0;
    };
    struct Side {
        int32_t patch = 0;
        bool back = false;
    };

    // Fails for what RadiosityLimitation names, which radiosity does not model, for a sphere
    // (TessellateSpheres meshes them first) and for a split cell that is not in the mesh.
    static absl::StatusOr<PatchMesh> Build(const Scene& scene, const PatchMeshOptions& options);

    // The patch size used (derived from the target count if the options gave none).
    double patch_size() const { return patch_size_; }
    const std::vector<Vec3d>& vertices() const { return vertices_; }  // world space
    const std::vector<Patch>& patches() const { return patches_; }
    // Sorted by mesh, then front sides before back sides, then triangle and sub-triangle, so
    // runs of consecutive sides lie on one side of one surface.
    const std::vector<Side>& sides() const { return sides_; }
    // The split cells, sorted: with the patch size, all it takes to build this mesh again.
    const std::vector<PatchCell>& split() const { return split_; }

    int Subdivision(int mesh, int primitive) const { return triangle(mesh, primitive).k; }
    // Unit normal of the front face (that of the scene triangle).
    const Vec3d& Normal(int64_t patch) const;
    // Unit normal of a side: the front normal, flipped for a back side.
    Vec3d SideNormal(int32_t side) const;
    Vec3d Centroid(int64_t patch) const;
    PatchCell Cell(int64_t patch) const;

    // The patch containing barycentric point (b1, b2) of a scene triangle.
    PatchPoint Locate(int mesh, int primitive, double b1, double b2) const;
    // Barycentrics (b1, b2) in the scene triangle of the patch point with weights w.
    std::array<double, 2> TriangleBarycentrics(int64_t patch, const std::array<double, 3>& w) const;

  private:
    struct Triangle {
        int32_t k = 1;
        int64_t first_patch = 0, end_patch = 0;
        int64_t first_node = 0;  // nodes_ of the k^2 coarse cells, in patch order
        Vec3d normal;
    };

    const Triangle& triangle(int mesh, int primitive) const {
        return triangles_[size_t(mesh_first_triangle_[size_t(mesh)] + primitive)];
    }

    double patch_size_ = 0;
    std::vector<Vec3d> vertices_;
    std::vector<Patch> patches_;
    std::vector<Side> sides_;
    std::vector<PatchCell> split_;
    std::vector<Triangle> triangles_;
    // The cell tree: a node >= 0 is a patch; ~node is the first of a split cell's four quarters
    // (the quarters at corners 0, 1, 2 of the cell, then the middle one).
    std::vector<int64_t> nodes_;
    std::vector<int64_t> mesh_first_triangle_;
};

}  // namespace lf
