// --camera and --resolution: the view of a scene, for every command that loads one (render,
// plan, converge, bench, submit).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "absl/status/status.h"
#include "lf/core/scene_loader.h"

namespace lf {

// "WxH" ("1920x1080") into *width and *height; a bare "N" too when `single` is not null (then
// *single = N and the size is left alone). InvalidArgument otherwise.
absl::Status ParseResolution(const std::string& text, int* width, int* height, int* single);

// --camera NAME, filling options.camera.
void AddCameraFlag(CLI::App* cmd, SceneOptions& options);

// --camera and --resolution WxH, filling `options`.
void AddSceneFlags(CLI::App* cmd, SceneOptions& options);

}  // namespace lf
