#include "lf/kernels/embree_scene.h"

#include <embree3/rtcore.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "absl/strings/str_cat.h"
#include "lf/core/scene_animation.h"
#include "lf/kernels/float_util.h"
#include "lf/kernels/shading.h"

namespace lf {

namespace {

// What a filtered mesh's filter function tests (the geometry's user data).
struct MeshFilter {
    const EmbreeScene* scene;
    int mesh;
    bool alpha_test;    // rays pass through holes (or blend) of the base colour's alpha
    bool single_sided;  // rays pass through back faces
};

}  // namespace

struct EmbreeScene::Handles {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<float> sphere_buffer;  // x,y,z,r per sphere
    std::vector<MeshFilter> filters;   // per mesh that needs a filter function
};

namespace {

// Strictly positive: an origin exactly on a surface (zero error bound, e.g. at coordinate 0 on
// an axis-aligned plane) must not hit that surface at t = 0.
constexpr float kTNear = std::numeric_limits<float>::min();

void OnEmbreeError(void*, RTCError code, const char* message) {
    if (code == RTC_ERROR_CANCELLED) return;  // asked for: Build says so
    spdlog::error("embree: error {}: {}", int(code), message ? message : "");
}

// False stops the build.
bool KeepBuilding(void* cancel, double) {
    return !static_cast<const std::atomic<bool>*>(cancel)->load(std::memory_order_relaxed);
}

// Each per-vertex attribute is absent or given for every vertex; texture refs name an image.
absl::Status CheckMesh(const Scene& scene, const TriangleMesh& mesh) {
    const size_t n = mesh.positions.size();
    const auto check = [&](size_t size, const char* what) -> absl::Status {
        if (size == 0 || size == n) return absl::OkStatus();
        return absl::InvalidArgumentError(absl::StrCat(scene.source, ": mesh '", mesh.name,
                                                       "' has ", size, " ", what, " for ", n,
                                                       " vertices"));
    };
    if (absl::Status s = check(mesh.normals.size(), "normals"); !s.ok()) return s;
    if (absl::Status s = check(mesh.uvs.size(), "texture coordinates"); !s.ok()) return s;
    if (absl::Status s = check(mesh.uvs1.size(), "second texture coordinates"); !s.ok()) return s;
    if (absl::Status s = check(mesh.colors.size(), "vertex colours"); !s.ok()) return s;
    return check(mesh.tangents.size(), "tangents");
}

absl::Status CheckTextures(const Scene& scene, const Material& m) {
    for (const TextureRef* ref :
         {&m.base_color_texture, &m.metallic_roughness_texture, &m.normal_texture,
          &m.emission_texture, &m.transmission_texture}) {
        if (!ref->valid()) continue;
        if (size_t(ref->image) >= scene.textures.size() || !scene.textures[size_t(ref->image)]) {
            return absl::InvalidArgumentError(absl::StrCat(scene.source, ": material '", m.name,
                                                           "' uses texture ", ref->image, " of ",
                                                           scene.textures.size()));
        }
    }
    return absl::OkStatus();
}

Vec3 RayOrigin(const RTCFilterFunctionNArguments* args, unsigned i) {
    return {RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
            RTCRayN_org_z(args->ray, args->N, i)};
}

Vec3 RayDirection(const RTCFilterFunctionNArguments* args, unsigned i) {
    return {RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
            RTCRayN_dir_z(args->ray, args->N, i)};
}

// Embree calls this for every candidate hit on a filtered mesh, before accepting it.
void FilterHits(const RTCFilterFunctionNArguments* args) {
    const auto& f = *static_cast<const MeshFilter*>(args->geometryUserPtr);
    const Scene& scene = f.scene->scene();
    const TriangleMesh& mesh = scene.meshes[size_t(f.mesh)];
    const Material& material = scene.materials[size_t(mesh.material)];
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const int prim = int(RTCHitN_primID(args->hit, args->N, i));
        if (f.single_sided) {
            const Vec3 d = RayDirection(args, i);
            Vec3 p0, p1, p2;
            f.scene->Triangle(f.mesh, prim, RTCRayN_time(args->ray, args->N, i), &p0, &p1, &p2);
            if (Dot(d, Cross(p1 - p0, p2 - p0)) > 0) {
                args->valid[i] = 0;
                continue;
            }
        }
        if (f.alpha_test) {
            const float b1 = RTCHitN_u(args->hit, args->N, i),
                        b2 = RTCHitN_v(args->hit, args->N, i);
            const float u = material.alpha_mode == Material::AlphaMode::kBlend
                                ? AlphaHash(RayOrigin(args, i), RayDirection(args, i),
                                            unsigned(f.mesh), unsigned(prim))
                                : 0;
            if (PassesThrough(scene, material, TriangleUvs(mesh, prim, b1, b2),
                              VertexColor(mesh, prim, b1, b2).a, u)) {
                args->valid[i] = 0;
            }
        }
    }
}

// Where `time` falls among `steps` poses: between pose i and i + 1, a fraction f past i, as
// Embree's motion blur interpolates.
struct StepPosition {
    size_t i;
    float f;
};
StepPosition StepAt(float time, size_t steps) {
    const float x = std::clamp(time, 0.0f, 1.0f) * float(steps - 1);
    const size_t i = std::min(size_t(x), steps - 2);
    return {i, x - float(i)};
}

template <typename T>
T Lerp(const T& a, const T& b, float f) {
    return a * (1 - f) + b * f;
}

// The places of the point and spot lights in `scene`, render space.
Vec3 PointPlace(const Scene& scene, size_t i, const Vec3d& origin) {
    return Vec3(scene.point_lights[i].position - origin);
}
EmbreeScene::SpotPlace SpotPlaceOf(const Scene& scene, size_t i, const Vec3d& origin) {
    const SpotLight& spot = scene.spot_lights[i];
    return {Vec3(spot.position - origin), Vec3(Normalize(spot.direction))};
}

// What moves over the shutter, posed at MotionSteps(motion) times: meshes, camera, lights.
struct PosedSteps {
    std::vector<std::vector<EmbreeScene::MeshStep>>& meshes;
    std::vector<CameraSpec>& camera;
    std::vector<std::vector<Vec3>>& points;
    std::vector<std::vector<EmbreeScene::SpotPlace>>& spots;
    std::vector<std::vector<float>>& spheres;  // per step, x y z r per sphere; empty: none moves
};
absl::Status PoseSteps(const Scene& scene, const SceneMotion& motion, int steps,
                       const Vec3d& origin, const PosedSteps& out) {
    const SceneAnimation& animation = *motion.animation;
    const std::vector<bool> moving_nodes = animation.MovingNodes();
    const bool camera_moves =
        animation.camera_node >= 0 && moving_nodes[size_t(animation.camera_node)];
    const bool spheres_move = std::any_of(animation.spheres.begin(), animation.spheres.end(),
                                          [](const AnimatedSphere& s) { return s.moves; });
    Scene posed = scene;
    for (int i = 0; i < steps; ++i) {
        const double t = i + 1 == steps
                             ? motion.close
                             : motion.open + (motion.close - motion.open) * i / (steps - 1);
        if (absl::Status s = animation.PoseAt(t, posed); !s.ok()) return s;
        for (const AnimatedMesh& am : animation.meshes) {
            if (!am.moves) continue;
            const TriangleMesh& mesh = posed.meshes[size_t(am.mesh)];
            EmbreeScene::MeshStep step;
            step.positions.reserve(mesh.positions.size() + 1);
            for (const Vec3d& p : mesh.positions) step.positions.push_back(Vec3(p - origin));
            step.positions.push_back(Vec3());  // Embree may read 16 bytes from the last vertex
            step.normals = mesh.normals;
            step.tangents = mesh.tangents;
            out.meshes[size_t(am.mesh)].push_back(std::move(step));
        }
        if (camera_moves) out.camera.push_back(posed.camera);
        if (spheres_move) {
            std::vector<float>& step = out.spheres.emplace_back();
            step.reserve(4 * posed.spheres.size());
            for (const Sphere& s : posed.spheres) {
                const Vec3 c(s.center - origin);
                step.insert(step.end(), {c.x, c.y, c.z, float(s.radius)});
            }
        }
        for (const AnimatedLight& light : animation.lights) {
            if (!light.moves) continue;
            const size_t i = size_t(light.index);
            if (light.kind == AnimatedLight::Kind::kPoint) {
                out.points[i].push_back(PointPlace(posed, i, origin));
            } else if (light.kind == AnimatedLight::Kind::kSpot) {
                out.spots[i].push_back(SpotPlaceOf(posed, i, origin));
            }
        }
    }
    return absl::OkStatus();
}

}  // namespace

Vec3 OffsetRayOrigin(const SurfacePoint& sp, const Vec3& w) {
    const float d = Dot(Abs(sp.n), sp.p_error);
    Vec3 offset = sp.n * d;
    if (Dot(w, sp.n) < 0) offset = -offset;
    Vec3 po = sp.p + offset;
    for (int i = 0; i < 3; ++i) {
        if (offset[i] > 0) {
            po[i] = NextFloatUp(po[i]);
        } else if (offset[i] < 0) {
            po[i] = NextFloatDown(po[i]);
        }
    }
    return po;
}

Ray SpawnRay(const SurfacePoint& from, const Vec3& direction) {
    Ray ray{OffsetRayOrigin(from, direction), direction};
    ray.time = from.time;
    return ray;
}

Ray SpawnRayTo(const SurfacePoint& from, const SurfacePoint& to) {
    const Vec3 o = OffsetRayOrigin(from, to.p - from.p);
    const Vec3 target = OffsetRayOrigin(to, o - to.p);
    constexpr float kShadowEpsilon = 1e-4f;
    return Ray{o, target - o, 1 - kShadowEpsilon, from.time};
}

EmbreeScene::EmbreeScene(const Scene& scene, const Vec3d& origin)
    : scene_(scene), origin_(origin), handles_(std::make_unique<Handles>()) {}

EmbreeScene::~EmbreeScene() {
    if (handles_->scene) rtcReleaseScene(handles_->scene);
    if (handles_->device) rtcReleaseDevice(handles_->device);
}

namespace {

// What the time steps do not move yet (a sphere's radius, directional lights) must not sit still
// silently while the rest blurs: refused, naming the object. `sphere_steps` are PoseSteps'.
absl::Status CheckMotionIsRepresented(const SceneAnimation& animation,
                                      const std::vector<std::vector<float>>& sphere_steps) {
    for (const AnimatedSphere& s : animation.spheres) {
        if (!s.moves) continue;
        const size_t r = 4 * size_t(s.sphere) + 3;
        for (const std::vector<float>& step : sphere_steps) {
            // A rotating node may round its scale differently step to step.
            if (std::abs(step[r] - sphere_steps.front()[r]) <= 1e-5f * step[r]) continue;
            return absl::UnimplementedError(
                absl::StrCat("spheres[", s.sphere, "] (", animation.nodes[size_t(s.node)].where,
                             ") changes size during the shutter (radius ", sphere_steps.front()[r],
                             " to ", step[r],
                             "), and motion blur of a scaling analytic sphere is not implemented: "
                             "make it a mesh (a UV sphere) or render without --shutter"));
        }
    }
    for (const AnimatedLight& l : animation.lights) {
        if (!l.moves || l.kind != AnimatedLight::Kind::kDirectional) continue;
        return absl::UnimplementedError(
            absl::StrCat("directional light ", l.index, " (", animation.nodes[size_t(l.node)].where,
                         ") turns during the shutter, and motion blur of directional lights is not "
                         "implemented yet: render without --shutter"));
    }
    return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::unique_ptr<EmbreeScene>> EmbreeScene::Build(const Scene& scene,
                                                                const std::atomic<bool>* cancel,
                                                                const SceneMotion& motion) {
    const auto [lo, hi] = scene.Bounds();
    const Vec3d origin = (lo + hi) * 0.5;
    std::unique_ptr<EmbreeScene> es(new EmbreeScene(scene, origin));
    es->media_ = std::make_unique<SceneMedia>(scene, origin);
    Handles& h = *es->handles_;
    h.device = rtcNewDevice(nullptr);
    if (!h.device) return absl::InternalError("embree: cannot create a device");
    rtcSetDeviceErrorFunction(h.device, OnEmbreeError, nullptr);
    h.scene = rtcNewScene(h.device);
    // Robust mode keeps the triangle test watertight along shared edges: no light leaks.
    rtcSetSceneFlags(h.scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(h.scene, RTC_BUILD_QUALITY_HIGH);
    if (cancel) {
        rtcSetSceneProgressMonitorFunction(h.scene, KeepBuilding,
                                           const_cast<void*>(static_cast<const void*>(cancel)));
    }

    for (const Material& m : scene.materials) {
        if (absl::Status s = CheckTextures(scene, m); !s.ok()) return s;
    }
    static_assert(sizeof(Vec3) == 3 * sizeof(float), "Embree reads positions_ as FLOAT3");
    es->positions_.resize(scene.meshes.size());
    es->steps_ = MotionSteps(motion);
    es->steps_of_.resize(scene.meshes.size());
    es->point_steps_.resize(scene.point_lights.size());
    es->spot_steps_.resize(scene.spot_lights.size());
    if (es->steps_ > 1) {
        if (absl::Status s = PoseSteps(scene, motion, es->steps_, origin,
                                       {es->steps_of_, es->camera_motion_, es->point_steps_,
                                        es->spot_steps_, es->sphere_steps_});
            !s.ok()) {
            return s;
        }
        if (absl::Status s = CheckMotionIsRepresented(*motion.animation, es->sphere_steps_);
            !s.ok()) {
            return s;
        }
    }
    // Filters hold pointers into this vector: sized once, never reallocated.
    h.filters.reserve(scene.meshes.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const TriangleMesh& mesh = scene.meshes[m];
        if (absl::Status s = CheckMesh(scene, mesh); !s.ok()) return s;
        std::vector<Vec3>& pos = es->positions_[m];
        pos.reserve(mesh.positions.size() + 1);
        for (const Vec3d& p : mesh.positions) pos.push_back(Vec3(p - origin));
        pos.push_back(Vec3());  // Embree may read 16 bytes from the last vertex
        RTCGeometry geom = rtcNewGeometry(h.device, RTC_GEOMETRY_TYPE_TRIANGLE);
        const std::vector<MeshStep>& steps = es->steps_of_[m];
        if (steps.empty()) {
            rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       pos.data(), 0, sizeof(Vec3), mesh.positions.size());
        } else {
            rtcSetGeometryTimeStepCount(geom, unsigned(steps.size()));
            for (size_t i = 0; i < steps.size(); ++i) {
                rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, unsigned(i),
                                           RTC_FORMAT_FLOAT3, steps[i].positions.data(), 0,
                                           sizeof(Vec3), mesh.positions.size());
            }
        }
        rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                   mesh.triangles.data(), 0, 3 * sizeof(uint32_t),
                                   mesh.triangles.size());
        const Material& material = scene.materials[size_t(mesh.material)];
        const bool alpha_test = material.alpha_mode != Material::AlphaMode::kOpaque;
        const bool single_sided = !material.double_sided && !Transmits(material);
        // Ordinary meshes keep Embree's fast path: no callback per candidate hit.
        if (alpha_test || single_sided) {
            h.filters.push_back({es.get(), int(m), alpha_test, single_sided});
            rtcSetGeometryUserData(geom, &h.filters.back());
            rtcSetGeometryIntersectFilterFunction(geom, FilterHits);
            rtcSetGeometryOccludedFilterFunction(geom, FilterHits);
        }
        rtcCommitGeometry(geom);
        const unsigned id = rtcAttachGeometry(h.scene, geom);
        rtcReleaseGeometry(geom);
        if (id != m) return absl::InternalError("embree: unexpected geometry id");
    }
    if (!scene.spheres.empty()) {
        for (const Sphere& s : scene.spheres) {
            const Vec3 c(s.center - origin);
            es->sphere_centers_.push_back(c);
            h.sphere_buffer.insert(h.sphere_buffer.end(), {c.x, c.y, c.z, float(s.radius)});
        }
        RTCGeometry geom = rtcNewGeometry(h.device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
        if (es->sphere_steps_.empty()) {
            rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                       h.sphere_buffer.data(), 0, 4 * sizeof(float),
                                       scene.spheres.size());
        } else {
            rtcSetGeometryTimeStepCount(geom, unsigned(es->sphere_steps_.size()));
            for (size_t i = 0; i < es->sphere_steps_.size(); ++i) {
                rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, unsigned(i),
                                           RTC_FORMAT_FLOAT4, es->sphere_steps_[i].data(), 0,
                                           4 * sizeof(float), scene.spheres.size());
            }
        }
        rtcCommitGeometry(geom);
        es->sphere_geometry_ = rtcAttachGeometry(h.scene, geom);
        rtcReleaseGeometry(geom);
    }
    rtcCommitScene(h.scene);
    if (cancel && cancel->load()) return absl::CancelledError("embree: scene build cancelled");
    if (rtcGetDeviceError(h.device) != RTC_ERROR_NONE) {
        return absl::InternalError("embree: scene build failed (see log)");
    }
    return es;
}

void EmbreeScene::Triangle(int mesh, int primitive, float time, Vec3* p0, Vec3* p1,
                           Vec3* p2) const {
    const auto& tri = scene_.meshes[size_t(mesh)].triangles[size_t(primitive)];
    const std::vector<MeshStep>& steps = steps_of_[size_t(mesh)];
    if (steps.empty()) {
        const std::vector<Vec3>& pos = positions_[size_t(mesh)];
        *p0 = pos[tri[0]];
        *p1 = pos[tri[1]];
        *p2 = pos[tri[2]];
        return;
    }
    const StepPosition at = StepAt(time, steps.size());
    const std::vector<Vec3>&a = steps[at.i].positions, &b = steps[at.i + 1].positions;
    *p0 = Lerp(a[tri[0]], b[tri[0]], at.f);
    *p1 = Lerp(a[tri[1]], b[tri[1]], at.f);
    *p2 = Lerp(a[tri[2]], b[tri[2]], at.f);
}

float EmbreeScene::TriangleArea(int mesh, int primitive, float time) const {
    Vec3 p0, p1, p2;
    Triangle(mesh, primitive, time, &p0, &p1, &p2);
    return TriangleAreaOf(p0, p1, p2);
}

Vec3 EmbreeScene::Normal(int mesh, uint32_t v, float time) const {
    const std::vector<MeshStep>& steps = steps_of_[size_t(mesh)];
    if (steps.empty()) return scene_.meshes[size_t(mesh)].normals[v];
    const StepPosition at = StepAt(time, steps.size());
    return Lerp(steps[at.i].normals[v], steps[at.i + 1].normals[v], at.f);
}

std::array<float, 4> EmbreeScene::Tangent(int mesh, uint32_t v, float time) const {
    const std::vector<MeshStep>& steps = steps_of_[size_t(mesh)];
    if (steps.empty() || steps[0].tangents.empty()) return scene_.meshes[size_t(mesh)].tangents[v];
    const StepPosition at = StepAt(time, steps.size());
    const std::array<float, 4>&a = steps[at.i].tangents[v], &b = steps[at.i + 1].tangents[v];
    return {Lerp(a[0], b[0], at.f), Lerp(a[1], b[1], at.f), Lerp(a[2], b[2], at.f), a[3]};
}

Vec3 EmbreeScene::SphereCenter(int sphere, float time) const {
    if (sphere_steps_.empty()) return sphere_centers_[size_t(sphere)];
    const StepPosition at = StepAt(time, sphere_steps_.size());
    const float *a = &sphere_steps_[at.i][4 * size_t(sphere)],
                *b = &sphere_steps_[at.i + 1][4 * size_t(sphere)];
    return Lerp(Vec3(a[0], a[1], a[2]), Vec3(b[0], b[1], b[2]), at.f);
}

Vec3 EmbreeScene::PointLightPosition(int i, float time) const {
    const std::vector<Vec3>& steps = point_steps_[size_t(i)];
    if (steps.empty()) return PointPlace(scene_, size_t(i), origin_);
    const StepPosition at = StepAt(time, steps.size());
    return Lerp(steps[at.i], steps[at.i + 1], at.f);
}

EmbreeScene::SpotPlace EmbreeScene::SpotLightAt(int i, float time) const {
    const std::vector<SpotPlace>& steps = spot_steps_[size_t(i)];
    if (steps.empty()) return SpotPlaceOf(scene_, size_t(i), origin_);
    const StepPosition at = StepAt(time, steps.size());
    const SpotPlace &a = steps[at.i], &b = steps[at.i + 1];
    return {Lerp(a.position, b.position, at.f), Normalize(Lerp(a.direction, b.direction, at.f))};
}

SurfacePoint EmbreeScene::TrianglePoint(int mesh, int primitive, float b1, float b2,
                                        float time) const {
    Vec3 p0, p1, p2;
    Triangle(mesh, primitive, time, &p0, &p1, &p2);
    const float b0 = 1 - b1 - b2;
    SurfacePoint sp;
    // Interpolating the vertices keeps the point on the triangle's plane up to rounding;
    // the bound is pbrt-v4's for barycentric interpolation, widened on a moving mesh for the
    // interpolation in time, whose rounding Embree's may not share.
    sp.p = p0 * b0 + p1 * b1 + p2 * b2;
    sp.p_error = (Abs(p0 * b0) + Abs(p1 * b1) + Abs(p2 * b2)) * Gamma(Moves(mesh) ? 10 : 7);
    sp.time = time;
    sp.n = Normalize(Cross(p1 - p0, p2 - p0));
    sp.mesh = mesh;
    sp.primitive = primitive;
    sp.b1 = b1;
    sp.b2 = b2;
    return sp;
}

SurfacePoint EmbreeScene::SpherePoint(int sphere, const Vec3& direction_from_center,
                                      float time) const {
    const Vec3 c = SphereCenter(sphere, time);
    const float r = float(scene_.spheres[size_t(sphere)].radius);
    SurfacePoint sp;
    sp.n = Normalize(direction_from_center);
    const Vec3 local = sp.n * r;
    sp.p = c + local;
    // Reprojection onto the sphere (pbrt-v4) plus the rounding of adding the centre.
    sp.p_error = Abs(local) * Gamma(5) + Abs(sp.p) * Gamma(1);
    sp.time = time;
    return sp;
}

std::optional<SurfaceHit> EmbreeScene::Intersect(const Ray& ray) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = ray.o.x;
    rh.ray.org_y = ray.o.y;
    rh.ray.org_z = ray.o.z;
    rh.ray.dir_x = ray.d.x;
    rh.ray.dir_y = ray.d.y;
    rh.ray.dir_z = ray.d.z;
    rh.ray.tnear = kTNear;
    rh.ray.tfar = ray.t_max;
    rh.ray.mask = ~0u;
    rh.ray.flags = 0;
    rh.ray.time = ray.time;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(handles_->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;

    SurfaceHit hit;
    hit.t = rh.ray.tfar;
    hit.time = ray.time;
    SurfacePoint sp;
    if (rh.hit.geomID == sphere_geometry_) {
        hit.sphere = int(rh.hit.primID);
        hit.material = scene_.spheres[rh.hit.primID].material;
        const Vec3 p = ray.o + ray.d * hit.t;
        sp = SpherePoint(hit.sphere, p - SphereCenter(hit.sphere, ray.time), ray.time);
    } else {
        hit.mesh = int(rh.hit.geomID);
        hit.primitive = int(rh.hit.primID);
        hit.material = scene_.meshes[rh.hit.geomID].material;
        hit.b1 = rh.hit.u;
        hit.b2 = rh.hit.v;
        sp = TrianglePoint(hit.mesh, hit.primitive, hit.b1, hit.b2, ray.time);
    }
    hit.p = sp.p;
    hit.p_error = sp.p_error;
    hit.n = sp.n;
    return hit;
}

bool EmbreeScene::Occluded(const Ray& ray) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r;
    r.org_x = ray.o.x;
    r.org_y = ray.o.y;
    r.org_z = ray.o.z;
    r.dir_x = ray.d.x;
    r.dir_y = ray.d.y;
    r.dir_z = ray.d.z;
    r.tnear = kTNear;
    r.tfar = ray.t_max;
    r.mask = ~0u;
    r.flags = 0;
    r.time = ray.time;
    rtcOccluded1(handles_->scene, &context, &r);
    return r.tfar < 0;
}

}  // namespace lf
