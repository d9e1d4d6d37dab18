// Per-vertex tangents for normal maps, for meshes whose file gives none (OBJ, PLY, JSON, and
// glTF files without TANGENT).
#pragma once

#include "lf/core/scene.h"

namespace lf {

// Fills mesh.tangents from uv set `tex_coord` (mesh.uvs for 0, mesh.uvs1 for 1; it must be
// set), the one the normal map reads: each triangle's directions of increasing u and of
// decreasing v (up in the image, the normal map's +Y) summed at its corners, then made
// orthogonal to the vertex normal (the face normals' sum where the mesh has none), w the
// bitangent's sign. MikkTSpace, which glTF's specification points to, also weights by corner
// angle and splits vertices at uv seams; this does neither.
void ComputeTangents(TriangleMesh& mesh, int tex_coord = 0);

// ComputeTangents for every mesh whose material has a normal map, that has the uv set
// the map reads and no tangents.
void ComputeMissingTangents(Scene& scene);

}  // namespace lf
