// Triangle meshes from Wavefront OBJ (tinyobjloader) and PLY (ASCII and binary).
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"

namespace lf {

// Polygons are fan-triangulated. Errors name the file and, where known, the line or element.
absl::StatusOr<TriangleMesh> LoadMesh(const std::string& path);

}  // namespace lf
