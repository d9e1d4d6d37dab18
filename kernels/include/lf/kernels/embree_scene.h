// The scene converted once into Embree geometry. Geometry lives in "render space": world
// positions minus origin() (the centre of the scene's bounds), converted to float only after
// that subtraction, so a scene 10^5 units from the world origin keeps full float precision.
// Hit points carry pbrt-v4 style floating-point error bounds; rays leaving a surface start
// beyond them (SpawnRay), so there is no self-intersection at any scale.
// With motion (SceneMotion) the meshes that move have one pose per step over the shutter
// (Embree's time steps, interpolated linearly); everything that reads a position, normal or
// tangent at a time (a ray's, a hit's) interpolates the same way, so a light sample on a moving
// emitter and a ray's hit on it agree. Meshes that stay still keep one pose and cost nothing.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/ray.h"
#include "lf/core/scene.h"
#include "lf/kernels/media.h"
#include "lf/kernels/scene_motion.h"

namespace lf {

struct SurfaceHit {
    float t = 0;
    Vec3 p;        // render space
    Vec3 p_error;  // absolute error bound of p per axis
    Vec3 n;        // unit geometric normal of the front face
    int material = 0;
    int mesh = -1;         // index in Scene::meshes, or -1 for a sphere
    int sphere = -1;       // index in Scene::spheres, or -1 for a triangle
    int primitive = 0;     // triangle index within the mesh
    float b1 = 0, b2 = 0;  // barycentrics of vertices 1 and 2 of the triangle
    float time = 0;        // the ray's (Ray::time): where moving geometry was hit
};

// A point on a surface with its error bound and normal: where rays start and end.
struct SurfacePoint {
    Vec3 p, p_error, n;
    // The triangle it lies on, when it came from TrianglePoint (light samples): lets the path
    // tracer read the emitter's textures there. mesh -1 otherwise.
    int mesh = -1, primitive = 0;
    float b1 = 0, b2 = 0;
    float time = 0;  // in the shutter (Ray::time): rays spawned from it leave then
};

// A hit as a point rays leave from, with its geometric normal and no shading: where a ray
// crossing an interface surface goes on from.
inline SurfacePoint HitPoint(const SurfaceHit& hit) {
    return {.p = hit.p, .p_error = hit.p_error, .n = hit.n, .time = hit.time};
}

// A ray origin just outside p's error box on the side of w.
// The area of the triangle p0 p1 p2: the one formula of the light lists and their densities.
inline float TriangleAreaOf(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
    return 0.5f * Length(Cross(p1 - p0, p2 - p0));
}

Vec3 OffsetRayOrigin(const SurfacePoint& sp, const Vec3& w);
Ray SpawnRay(const SurfacePoint& from, const Vec3& direction);
// A ray from `from` that stops just short of `to`: t in (0, 1 - epsilon) over d = to' - from'.
Ray SpawnRayTo(const SurfacePoint& from, const SurfacePoint& to);

class EmbreeScene {
  public:
    // Cancelled once `cancel` is set: Embree's BVH build asks its progress monitor often.
    // `scene` is posed at the frame's time; with `motion` that blurs, copies of it posed at
    // MotionSteps(motion) times over the shutter (SceneAnimation::PoseAt) give the moving
    // meshes' steps and the camera's (camera_motion()). A pose PoseAt refuses is the error.
    static absl::StatusOr<std::unique_ptr<EmbreeScene>> Build(
        const Scene& scene, const std::atomic<bool>* cancel = nullptr,
        const SceneMotion& motion = {});
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    // Neither sees alpha-mask holes nor the back faces of single-sided, non-transmissive meshes:
    // Embree filter functions on just those meshes skip such hits.
    std::optional<SurfaceHit> Intersect(const Ray& ray) const;
    bool Occluded(const Ray& ray) const;

    const Scene& scene() const { return scene_; }
    const Vec3d& origin() const { return origin_; }
    // The scene's participating media in render space.
    const SceneMedia& media() const { return *media_; }

    // Sphere `sphere`'s centre (render space) at `time` (Ray::time): the Scene's when no sphere
    // moves, else linear between steps, as Embree moves it. Its radius stays the Scene's: Build
    // refuses a blur that would scale one.
    Vec3 SphereCenter(int sphere, float time) const;
    // Vertices of triangle `primitive` of `mesh` in render space at `time` (Ray::time).
    void Triangle(int mesh, int primitive, float time, Vec3* p0, Vec3* p1, Vec3* p2) const;
    SurfacePoint TrianglePoint(int mesh, int primitive, float b1, float b2, float time) const;
    // Its area at `time`: a deforming triangle's changes with time (TriangleAreaOf).
    float TriangleArea(int mesh, int primitive, float time) const;
    SurfacePoint SpherePoint(int sphere, const Vec3& direction_from_center, float time) const;
    // Whether mesh m moves during the shutter; its vertex `v`'s normal and tangent at `time`
    // (the Scene's when it does not move; interpolated, not normalised, when it does).
    bool Moves(int mesh) const { return !steps_of_[size_t(mesh)].empty(); }
    Vec3 Normal(int mesh, uint32_t v, float time) const;
    std::array<float, 4> Tangent(int mesh, uint32_t v, float time) const;
    // Point light i's position and spot light i's position and unit axis (render space) at
    // `time`: the Scene's when no node moves them, else linear between steps (the axis
    // renormalised).
    Vec3 PointLightPosition(int i, float time) const;
    struct SpotPlace {
        Vec3 position, direction;
    };
    SpotPlace SpotLightAt(int i, float time) const;
    // The camera's poses over the shutter when it moves (for Camera's motion), else empty.
    const std::vector<CameraSpec>& camera_motion() const { return camera_motion_; }
    // How many poses moving meshes have (1: nothing moves).
    int steps() const { return steps_; }

    // A moving mesh's pose at one step: render-space positions with the padding vertex,
    // normals and tangents as the posed Scene gives them.
    struct MeshStep {
        std::vector<Vec3> positions, normals;
        std::vector<std::array<float, 4>> tangents;
    };

  private:
    EmbreeScene(const Scene& scene, const Vec3d& origin);

    const Scene& scene_;
    Vec3d origin_;
    struct Handles;
    std::unique_ptr<Handles> handles_;
    std::unique_ptr<SceneMedia> media_;
    // Render-space float positions per mesh, one padding vertex at the end: also Embree's vertex
    // buffer (shared, not copied). Normals, uvs and tangents are read from the Scene itself:
    // translation to render space leaves them unchanged.
    std::vector<std::vector<Vec3>> positions_;
    // Per mesh: empty when it stands still, else its poses, one per step.
    std::vector<std::vector<MeshStep>> steps_of_;
    // Per point and spot light: empty when it stands still, else its places, one per step.
    std::vector<std::vector<Vec3>> point_steps_;
    std::vector<std::vector<SpotPlace>> spot_steps_;
    int steps_ = 1;
    std::vector<CameraSpec> camera_motion_;
    std::vector<Vec3> sphere_centers_;
    // Empty when no sphere moves, else per step every sphere's x, y, z, r (Embree's buffers).
    std::vector<std::vector<float>> sphere_steps_;
    unsigned sphere_geometry_ = ~0u;
};

}  // namespace lf
