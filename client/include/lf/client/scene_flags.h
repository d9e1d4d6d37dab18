// --camera, --resolution and --filter: the view of a scene, for every command that loads one
// (render, plan, converge, bench, submit).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "lf/core/scene_loader.h"

namespace lf {

// --camera NAME, filling options.camera.
void AddCameraFlag(CLI::App* cmd, SceneOptions& options);

// --resolution WxH into options.width and height; with `single`, also a bare N (at most
// `max_single`) into *single, for the commands whose --resolution N came first.
void AddResolutionFlag(CLI::App* cmd, SceneOptions& options, int* single, int max_single,
                       const std::string& help);

// --filter TYPE[:WIDTH] into options.filter: the pixel filter, in place of the scene camera's.
inline constexpr double kDefaultFilterWidth = 3;  // pixels, gaussian and blackman-harris
void AddFilterFlag(CLI::App* cmd, SceneOptions& options);

// --camera, --resolution WxH and --filter, filling `options`.
void AddSceneFlags(CLI::App* cmd, SceneOptions& options);

}  // namespace lf
