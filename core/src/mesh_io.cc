#include "lf/core/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "lf/core/file_util.h"
#include "mesh_parse.h"

namespace lf {
namespace {

using mesh_internal::Fail, mesh_internal::MeshError, mesh_internal::ParseObj,
    mesh_internal::ParsePly;

absl::StatusOr<MeshFile> ParseMeshFile(const std::string& bytes, const std::string& name,
                                       const SceneFileReader* read_file) {
    std::string extension = std::filesystem::path(name).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (extension != ".obj" && extension != ".ply") {
        return absl::InvalidArgumentError(absl::StrCat(name, ": unknown mesh format \"", extension,
                                                       "\" (expected .obj or .ply)"));
    }
    try {
        MeshFile file;
        if (extension == ".obj") {
            file = ParseObj(bytes, name, read_file);
        } else {
            file.meshes.push_back(ParsePly(bytes));
            file.meshes[0].material = -1;
            file.unassigned_where.push_back(name);
            if (file.meshes[0].positions.empty()) Fail("", "no vertices");
            if (file.meshes[0].triangles.empty()) Fail("", "no faces");
        }
        for (TriangleMesh& mesh : file.meshes) {
            mesh.name = std::filesystem::path(name).stem().string();
        }
        return file;
    } catch (const MeshError& e) {
        return absl::InvalidArgumentError(absl::StrCat(name, e.where, ": ", e.message));
    }
}

}  // namespace

absl::StatusOr<TriangleMesh> ParseMesh(const std::string& bytes, const std::string& name) {
    absl::StatusOr<MeshFile> file = ParseMeshFile(bytes, name, nullptr);
    if (!file.ok()) return file.status();
    return std::move(file->meshes[0]);
}

absl::StatusOr<MeshFile> ParseMeshWithMaterials(const std::string& bytes, const std::string& name,
                                                const SceneFileReader& read_file) {
    return ParseMeshFile(bytes, name, &read_file);
}

absl::StatusOr<TriangleMesh> LoadMesh(const std::string& path) {
    absl::StatusOr<std::string> bytes = ReadFile(path);
    if (!bytes.ok()) return bytes.status();
    return ParseMesh(*bytes, path);
}

}  // namespace lf
