#include "lf/core/sphere_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <utility>

#include "lf/core/scene_animation.h"

namespace lf {

namespace {

// The unit icosphere: directions (positions and normals alike) and outward triangles.
struct UnitIcosphere {
    std::vector<Vec3d> directions;
    std::vector<std::array<uint32_t, 3>> triangles;
};

UnitIcosphere MakeUnitIcosphere(int n) {
    const double t = (1 + std::sqrt(5.0)) / 2;
    std::array<Vec3d, 12> corners = {{{-1, t, 0},
                                      {1, t, 0},
                                      {-1, -t, 0},
                                      {1, -t, 0},
                                      {0, -1, t},
                                      {0, 1, t},
                                      {0, -1, -t},
                                      {0, 1, -t},
                                      {t, 0, -1},
                                      {t, 0, 1},
                                      {-t, 0, -1},
                                      {-t, 0, 1}}};
    for (Vec3d& c : corners) c = Normalize(c);
    std::array<std::array<int, 3>, 20> faces = {
        {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
         {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
         {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}}};
    UnitIcosphere s;
    // A grid point on an icosahedron edge or corner is one vertex for every face that has it:
    // keyed by its weights on the corners, in corner order, so its position is computed once.
    std::map<std::array<int, 4>, uint32_t> shared;
    auto vertex = [&](std::array<std::pair<int, int>, 3> weights) {
        std::sort(weights.begin(), weights.end());
        const auto nonzero = std::remove_if(weights.begin(), weights.end(),
                                            [](const auto& w) { return w.second == 0; });
        const auto count = nonzero - weights.begin();
        auto make = [&] {
            Vec3d p;
            for (auto w = weights.begin(); w != nonzero; ++w) {
                p += corners[size_t(w->first)] * double(w->second);
            }
            s.directions.push_back(Normalize(p));
            return uint32_t(s.directions.size() - 1);
        };
        if (count == 3) return make();  // inside one face
        std::array<int, 4> key = {weights[0].first, weights[0].second, -1, 0};
        if (count == 2)
            key = {weights[0].first, weights[0].second, weights[1].first, weights[1].second};
        const auto [it, inserted] = shared.try_emplace(key, 0);
        if (inserted) it->second = make();
        return it->second;
    };
    for (std::array<int, 3> f : faces) {
        const Vec3d& a = corners[size_t(f[0])];
        if (Dot(Cross(corners[size_t(f[1])] - a, corners[size_t(f[2])] - a), a) < 0) {
            std::swap(f[1], f[2]);
        }
        // Grid point (i, j) of the face: weights n - i - j, i, j on its corners.
        std::vector<uint32_t> grid(size_t((n + 1) * (n + 1)));
        auto at = [&](int i, int j) -> uint32_t& { return grid[size_t(j * (n + 1) + i)]; };
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i + j <= n; ++i) {
                at(i, j) = vertex({{{f[0], n - i - j}, {f[1], i}, {f[2], j}}});
            }
        }
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i + j < n; ++i) {
                s.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
                if (i + j + 1 < n) {
                    s.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
                }
            }
        }
    }
    return s;
}

// The largest gap between a triangle's plane and the unit sphere.
double LargestGap(const UnitIcosphere& s) {
    double gap = 0;
    for (const auto& t : s.triangles) {
        const Vec3d& a = s.directions[t[0]];
        const Vec3d normal = Normalize(Cross(s.directions[t[1]] - a, s.directions[t[2]] - a));
        gap = std::max(gap, 1 - Dot(normal, a));
    }
    return gap;
}

}  // namespace

int SphereMeshFrequency(double tolerance) {
    int n = 1;
    while (n < kMaxSphereMeshFrequency && LargestGap(MakeUnitIcosphere(n)) > tolerance) ++n;
    return n;
}

TriangleMesh SphereMesh(const Sphere& sphere, int frequency) {
    const UnitIcosphere unit = MakeUnitIcosphere(frequency);
    TriangleMesh mesh;
    mesh.name = sphere.name;
    mesh.material = sphere.material;
    mesh.media = sphere.media;
    mesh.triangles = unit.triangles;
    for (const Vec3d& d : unit.directions) {
        mesh.positions.push_back(sphere.center + d * sphere.radius);
        mesh.normals.push_back(Vec3(d));
    }
    return mesh;
}

void TessellateSpheres(Scene& scene, double tolerance) {
    if (scene.spheres.empty()) return;
    const int frequency = SphereMeshFrequency(tolerance);
    const size_t first_mesh = scene.meshes.size();
    for (const Sphere& sphere : scene.spheres) {
        scene.meshes.push_back(SphereMesh(sphere, frequency));
    }
    if (scene.animation && !scene.animation->spheres.empty()) {
        // The node places the sphere's mesh as it placed the sphere: the loader keeps its scale
        // uniform, so the mesh stays a sphere of the radius the pose would give.
        auto animation = std::make_shared<SceneAnimation>(*scene.animation);
        for (const AnimatedSphere& s : animation->spheres) {
            const TriangleMesh local =
                SphereMesh({.center = s.center, .radius = s.radius}, frequency);
            AnimatedMesh& m = animation->meshes.emplace_back();
            m.mesh = int(first_mesh) + s.sphere;
            m.node = s.node;
            m.positions = local.positions;
            for (const Vec3& normal : local.normals) m.normals.push_back(Vec3d(normal));
            m.moves = s.moves;
        }
        animation->spheres.clear();
        scene.animation = std::move(animation);
    }
    scene.spheres.clear();
}

}  // namespace lf
