#include "scene_flags.h"

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"

namespace lf {

absl::Status ParseResolution(const std::string& text, int* width, int* height, int* single) {
    const size_t x = text.find_first_of("xX");
    int w = 0, h = 0;
    if (x == std::string::npos && single && absl::SimpleAtoi(text, &w) && w >= 0) {
        *single = w;
        return absl::OkStatus();
    }
    if (x == std::string::npos || !absl::SimpleAtoi(text.substr(0, x), &w) ||
        !absl::SimpleAtoi(text.substr(x + 1), &h) || w < 1 || h < 1) {
        return absl::InvalidArgumentError(absl::StrCat(
            "--resolution \"", text, "\": expected WxH, e.g. 1920x1080", single ? ", or N" : ""));
    }
    *width = w;
    *height = h;
    return absl::OkStatus();
}

void AddCameraFlag(CLI::App* cmd, SceneOptions& options) {
    cmd->add_option("--camera", options.camera,
                    "render from the glTF camera of this name (its node's name, or the "
                    "camera's); default: the JSON scene's camera, else the first glTF camera");
}

void AddSceneFlags(CLI::App* cmd, SceneOptions& options) {
    AddCameraFlag(cmd, options);
    cmd->add_option_function<std::string>(
           "--resolution",
           [&options](const std::string& text) {
               const absl::Status s = ParseResolution(text, &options.width, &options.height, nullptr);
               if (!s.ok()) throw CLI::ValidationError(std::string(s.message()));
           },
           "image size WxH in pixels, instead of the scene's (JSON resolution or glTF camera)")
        ->type_name("WxH");
}

}  // namespace lf
