// --camera, --resolution and --filter: the view of a scene, for every command that loads one
// (render, plan, converge, bench, submit); --sky, its environment light (render, submit).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "absl/status/status.h"
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

// --sky white|R,G,B|V|FILE into options.sky (lf/core/sky_option.h), checked as text; a file
// must then be resolved by ResolveSkyFile once the scene's path is known.
void AddSkyFlag(CLI::App* cmd, SceneOptions& options);

// A --sky file, named relative to the current directory, renamed relative to the scene's
// folder (what the scene loader and the farm read it by). NotFound when it is not a file.
absl::Status ResolveSkyFile(const std::string& scene_path, SceneOptions& options);

// --camera, --resolution and --filter, filling `options`.
void AddSceneFlags(CLI::App* cmd, SceneOptions& options);

}  // namespace lf
