// Scene files (docs/scene-format.md) to the validated scene model. Every error names the file
// and the JSON path (or the mesh file and line) so a user can fix it.
#pragma once

#include <functional>
#include <optional>
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

// What the user asks of a scene beyond its file (`--camera`, `--resolution`).
struct SceneOptions {
    // A glTF camera by its node's (or its own) name, also one of a glTF a JSON scene includes,
    // in place of the JSON's camera. Empty: the JSON's camera, else the first glTF camera.
    std::string camera;
    int width = 0, height = 0;  // above 0: the image size, whatever the scene says
    // `--filter`: the pixel filter, whatever the scene's camera says (glTF cameras have none).
    std::optional<PixelFilter> filter;
    // `--sky` (lf/core/sky_option.h): an environment light replacing the scene's; a map file by
    // the name the scene's reader reads it by. Empty: the scene's own.
    std::string sky;
};

// Files beside the scene file (ReadBeside of its folder).
absl::StatusOr<Scene> LoadScene(const std::string& path, const SceneOptions& options = {});

// `source` names the text in messages; a name ending in .gltf or .glb (any case) is a glTF 2.0
// file (lf/core/gltf_scene.h), anything else a JSON scene.
absl::StatusOr<Scene> ParseScene(const std::string& json_text, const std::string& source,
                                 const SceneFileReader& read_file,
                                 const SceneOptions& options = {});

}  // namespace lf
