// Analytic spheres as triangle meshes, for methods that take triangles only (radiosity): a
// geodesic icosphere, each icosahedron face cut n x n and its vertices pushed onto the sphere,
// with n the smallest frequency whose flat triangles stay within a tolerance of the sphere.
#pragma once

#include "lf/core/scene.h"

namespace lf {

// Default largest gap between a flat triangle and the sphere, relative to the radius: the
// tessellation's area is then 0.31 % below 4 pi r^2 (frequency 10, 2000 triangles).
inline constexpr double kSphereMeshTolerance = 3e-3;
// The finest frequency: 20 * 64^2 = 81920 triangles a sphere.
inline constexpr int kMaxSphereMeshFrequency = 64;

// The smallest icosphere frequency (each icosahedron face cut n x n) whose triangles' planes lie
// within `tolerance` x radius of the sphere, at most kMaxSphereMeshFrequency.
int SphereMeshFrequency(double tolerance);

// `sphere` as a closed mesh of 20 n^2 triangles: vertices on the sphere, shared between
// neighbours, wound outward, smooth normals (the radial directions); same name, material and
// media. Deterministic: the same sphere gives the same bits.
TriangleMesh SphereMesh(const Sphere& sphere, int frequency);

// Replaces every sphere of `scene` by its SphereMesh, appended to the meshes in sphere order,
// so what reads a mesh (the BVH, the patch mesh, the display) sees one tessellation. An
// animation that moves a sphere moves its mesh instead (rigidly, from the same node).
void TessellateSpheres(Scene& scene, double tolerance = kSphereMeshTolerance);

}  // namespace lf
