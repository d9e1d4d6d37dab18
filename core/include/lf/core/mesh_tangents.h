// Per-vertex tangents for normal maps, for meshes whose file gives none (OBJ, PLY, JSON, and
// glTF files without TANGENT).
#pragma once

#include "lf/core/scene.h"

namespace lf {

// Fills mesh.tangents (mesh.uvs must be set): each triangle's directions of increasing u and of
// decreasing v (up in the image, the normal map's +Y) summed at its corners, then made
// orthogonal to the vertex normal (the face normals' sum where the mesh has none), w the
// bitangent's sign. MikkTSpace, which glTF's specification points to, also weights by corner
// angle and splits vertices at uv seams; this does neither.
void ComputeTangents(TriangleMesh& mesh);

// ComputeTangents for every mesh whose material has a normal map, that has uvs and no tangents.
void ComputeMissingTangents(Scene& scene);

}  // namespace lf
