// Triangle meshes from Wavefront OBJ (tinyobjloader, with its MTL materials) and PLY (ASCII and
// binary), with per-vertex normals and texture coordinates when the file has them.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"
#include "lf/core/scene_loader.h"

namespace lf {

// What a mesh file brings to a scene: its triangles split by the material the file gives them,
// those materials, and the image files they name.
struct MeshFile {
    // An image file a material names, read and decoded by whoever builds the scene.
    struct Texture {
        std::string name;   // as the reader knows it: the MTL file's folder joined with its name
        std::string where;  // for messages: "models/car.mtl:12: map_Kd"
    };

    // One mesh per material, in the order the file first uses them. TriangleMesh::material
    // indexes `materials`, or is -1 for faces the file gives no material (all of them when the
    // file's materials were not read).
    std::vector<TriangleMesh> meshes;
    std::vector<Material> materials;  // their TextureRef::image index `textures`
    std::vector<Texture> textures;
    // Where the faces with material -1 start ("car.obj:12"), when the file's materials were
    // read: a loader needs one for them.
    std::vector<std::string> unassigned_where;
    std::vector<std::string> warnings;  // what the file asks for that is not modelled
};

// Polygons are fan-triangulated. Errors name the file and, where known, the line or element.
// OBJ texture coordinates have v = 0 at the bottom of the image: they are stored as 1 - v, the
// top-left origin of TriangleMesh::uvs; PLY's (u, v), (s, t) or (texture_u, texture_v) likewise.
absl::StatusOr<TriangleMesh> LoadMesh(const std::string& path);

// A mesh file's bytes, its format by the extension of `name`, which also names it in errors and
// gives the mesh its name: the scene loader parses files the same way wherever they are kept.
// Every face in one mesh; an OBJ's materials are not read.
absl::StatusOr<TriangleMesh> ParseMesh(const std::string& bytes, const std::string& name);

// As ParseMesh, and an OBJ's `mtllib` files are read through `read_file` (names relative to the
// folder of `name`), its faces split by `usemtl`. A missing or unreadable MTL file, or a
// `usemtl` of a material no MTL file defines, is an error naming the OBJ's line.
absl::StatusOr<MeshFile> ParseMeshWithMaterials(const std::string& bytes, const std::string& name,
                                                const SceneFileReader& read_file);

}  // namespace lf
