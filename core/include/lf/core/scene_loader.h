// Scene files (docs/scene-format.md) to the validated scene model. Every error names the file
// and the JSON path (or the mesh file and line) so a user can fix it.
#pragma once

#include <functional>
#include <string>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"

namespace lf {

// The files a scene names (meshes), by the name as written in the JSON: their bytes, or an error
// the loader reports after the JSON path ("shapes[2].file \"x.obj\": <error>"). The reader
// decides what a scene may reach: on the user's own disk anything (ReadBeside); on the farm only
// the files uploaded with the scene (lf::LoadSceneFromBlobs).
using SceneFileReader = std::function<absl::StatusOr<std::string>(const std::string& name)>;

// Relative names against `base_dir`, absolute ones as they are: a scene on the user's disk.
SceneFileReader ReadBeside(const std::string& base_dir);

// Files beside the scene file (ReadBeside of its folder).
absl::StatusOr<Scene> LoadScene(const std::string& path);

// `source` names the text in messages.
absl::StatusOr<Scene> ParseScene(const std::string& json_text, const std::string& source,
                                 const SceneFileReader& read_file);

}  // namespace lf
