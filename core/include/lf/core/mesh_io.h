// Triangle meshes from Wavefront OBJ (tinyobjloader) and PLY (ASCII and binary).
#pragma once

#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"

namespace lf {

// Polygons are fan-triangulated. Errors name the file and, where known, the line or element.
absl::StatusOr<TriangleMesh> LoadMesh(const std::string& path);

// A mesh file's bytes, its format by the extension of `name`, which also names it in errors and
// gives the mesh its name: the scene loader parses files the same way wherever they are kept.
absl::StatusOr<TriangleMesh> ParseMesh(const std::string& bytes, const std::string& name);

}  // namespace lf
