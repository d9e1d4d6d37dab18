// What the mesh file parsers (obj_mesh.cc, ply_mesh.cc) share with mesh_io.cc, which picks one
// by the file's extension. Private to core.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/mesh_io.h"
#include "lf/core/scene.h"
#include "lf/core/scene_loader.h"

namespace lf::mesh_internal {

// Parsers run deep loops; an error unwinds to LoadMesh as this exception, which adds the file
// name. `where` is ":LINE" when the line is known, otherwise empty.
struct MeshError {
    std::string where;
    std::string message;
};

[[noreturn]] inline void Fail(std::string where, std::string message) {
    throw MeshError{std::move(where), std::move(message)};
}

inline std::string LineSuffix(size_t line) { return line > 0 ? absl::StrCat(":", line) : ""; }

// A line's fields, split at spaces, tabs and carriage returns.
inline std::vector<std::string> SplitFields(std::string_view line) {
    std::vector<std::string> fields;
    size_t pos = 0;
    while ((pos = line.find_first_not_of(" \t\r", pos)) != std::string_view::npos) {
        const size_t end = std::min(line.find_first_of(" \t\r", pos), line.size());
        fields.emplace_back(line.substr(pos, end - pos));
        pos = end;
    }
    return fields;
}

// A Wavefront OBJ file `name`: one mesh per material its faces use; with `read_file` its MTL
// files are read and those materials converted, without it every face is in one mesh.
MeshFile ParseObj(const std::string& text, const std::string& name,
                  const SceneFileReader* read_file);

// A PLY file, ASCII or binary: its vertex and face elements as one mesh.
TriangleMesh ParsePly(std::string_view bytes);

}  // namespace lf::mesh_internal
