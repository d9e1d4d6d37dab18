// --camera, --resolution and --filter: the view of a scene, for every command that loads one
// (render, plan, converge, bench, submit).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "lf/core/scene_loader.h"

namespace lf {

// --camera NAME, filling options.camera.
void AddCameraFlag(CLI::App* cmd, SceneOptions& options);

// --resolution WxH, or N for N x N, into options.width and height (every command alike; the
// scene loader bounds them).
void AddResolutionFlag(CLI::App* cmd, SceneOptions& options, const std::string& help);

// --filter TYPE[:WIDTH] into options.filter: the pixel filter, in place of the scene camera's.
inline constexpr double kDefaultFilterWidth = 3;  // pixels, gaussian and blackman-harris
void AddFilterFlag(CLI::App* cmd, SceneOptions& options);

// --camera, --resolution and --filter, filling `options`.
void AddSceneFlags(CLI::App* cmd, SceneOptions& options);

}  // namespace lf
