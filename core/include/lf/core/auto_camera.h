// `--camera auto`: a camera that frames a scene without one (most glTF sample assets).
#pragma once

#include <string>

#include "lf/core/scene.h"

namespace lf {

// The name `--camera` takes for FrameScene, unless the scene has a camera of that name.
inline constexpr char kAutoCameraName[] = "auto";

// Looks at the centre of the scene's bounding sphere down -Z (glTF's front view, +Y up) from
// 20 degrees above, at the distance where the sphere just fits the vertical field of view of
// 40 degrees; 1024 x 768 pixels.
CameraSpec FrameScene(const Scene& scene);

}  // namespace lf
