// Scene files (docs/scene-format.md) to the validated scene model. Every error names the file
// and the JSON path (or the mesh file and line) so a user can fix it.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"

namespace lf {

absl::StatusOr<Scene> LoadScene(const std::string& path);

// `source` names the text in messages; relative mesh paths resolve against `base_dir`.
absl::StatusOr<Scene> ParseScene(const std::string& json_text, const std::string& source,
                                 const std::string& base_dir);

}  // namespace lf
