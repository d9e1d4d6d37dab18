// `--sky`: an environment light given on the command line (render, submit) instead of in a
// scene file. The scene loader applies it (SceneOptions::sky); the client resolves its file.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "lf/core/rgb.h"

namespace lf {

// `white` (radiance 1), `R,G,B` or a single number V (grey) in W m^-2 sr^-1, or else a
// lat-long map file (Radiance HDR or OpenEXR) read as a JSON environment's `file` is.
struct SkyOption {
    Rgb radiance{1.0f};  // uniform, when `file` is empty
    std::string file;
};

// InvalidArgument, naming `--sky` and the text, for an empty text or bad numbers (negative, not
// finite, above 1e10, or not one or three of them). Text made only of digits, signs, points,
// commas, spaces and e is numbers; anything else is a file name.
absl::StatusOr<SkyOption> ParseSkyOption(const std::string& text);

}  // namespace lf
