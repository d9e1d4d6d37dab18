#include "lf/client/scene_flags.h"

#include <filesystem>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/sky_option.h"

namespace lf {
namespace {

// "WxH" ("1920x1080") or "N" (N x N) into *width and *height; InvalidArgument otherwise.
absl::Status ParseResolution(const std::string& text, int* width, int* height) {
    const size_t x = text.find_first_of("xX");
    int w = 0, h = 0;
    const bool parsed =
        x == std::string::npos
            ? absl::SimpleAtoi(text, &w) && absl::SimpleAtoi(text, &h)
            : absl::SimpleAtoi(text.substr(0, x), &w) && absl::SimpleAtoi(text.substr(x + 1), &h);
    if (!parsed || w < 1 || h < 1) {
        return absl::InvalidArgumentError(absl::StrCat(
            "--resolution \"", text, "\": expected WxH, e.g. 1920x1080, or N for N x N"));
    }
    *width = w;
    *height = h;
    return absl::OkStatus();
}

// "TYPE" or "TYPE:WIDTH" (width in pixels; default 1 for box, kDefaultFilterWidth otherwise).
absl::StatusOr<PixelFilter> ParseFilter(const std::string& text) {
    const size_t colon = text.find(':');
    const std::string name = text.substr(0, colon);
    const std::optional<PixelFilter::Type> type = PixelFilterTypeFromName(name);
    if (!type) {
        return absl::InvalidArgumentError(absl::StrCat(
            "--filter ", text, ": unknown filter \"", name,
            "\"; expected box, gaussian or blackman-harris, optionally :WIDTH in pixels"));
    }
    PixelFilter filter{*type, *type == PixelFilter::Type::kBox ? 1.0 : kDefaultFilterWidth};
    if (colon != std::string::npos && !absl::SimpleAtod(text.substr(colon + 1), &filter.width)) {
        return absl::InvalidArgumentError(
            absl::StrCat("--filter ", text, ": the width after ':' must be a number of pixels"));
    }
    if (absl::Status s = CheckPixelFilter(filter); !s.ok()) {
        return absl::InvalidArgumentError(absl::StrCat("--filter ", text, ": ", s.message()));
    }
    return filter;
}

}  // namespace

void AddFilterFlag(CLI::App* cmd, SceneOptions& options) {
    cmd->add_option_function<std::string>(
           "--filter",
           [&options](const std::string& text) {
               absl::StatusOr<PixelFilter> filter = ParseFilter(text);
               if (!filter.ok()) throw CLI::ValidationError(std::string(filter.status().message()));
               options.filter = *filter;
           },
           absl::StrCat("pixel filter, in place of the scene camera's (default: the scene's, "
                        "else box): box (each sample uniform in its pixel), gaussian (sigma = "
                        "width/6) or blackman-harris, with an optional :WIDTH, the filter's full "
                        "support in pixels (",
                        kMinFilterWidth, " to ", kMaxFilterWidth, ", default ", kDefaultFilterWidth,
                        "; box is 1). Samples are placed by the filter, keeping equal weights"))
        ->type_name("TYPE[:WIDTH]");
}

void AddCameraFlag(CLI::App* cmd, SceneOptions& options) {
    cmd->add_option("--camera", options.camera,
                    "render from the glTF camera of this name (its node's name, or the "
                    "camera's), or the N-th glTF camera in node order (from 0) when none is "
                    "named N; `auto` frames the whole scene from the front (-Z, glTF's +Y up, 20 "
                    "degrees above), unless a camera is named so; default: the JSON scene's "
                    "camera, else the first glTF camera");
}

void AddResolutionFlag(CLI::App* cmd, SceneOptions& options, const std::string& help) {
    cmd->add_option_function<std::string>(
           "--resolution",
           [&options](const std::string& text) {
               absl::Status s = ParseResolution(text, &options.width, &options.height);
               if (!s.ok()) throw CLI::ValidationError(std::string(s.message()));
           },
           help)
        ->type_name("WxH|N");
}

void AddSkyFlag(CLI::App* cmd, SceneOptions& options) {
    cmd->add_option_function<std::string>(
           "--sky",
           [&options](const std::string& text) {
               absl::StatusOr<SkyOption> sky = ParseSkyOption(text);
               if (!sky.ok()) throw CLI::ValidationError(std::string(sky.status().message()));
               options.sky = text;
           },
           "an environment light in place of the scene's (with a warning when it has one), "
           "without writing JSON: white (radiance 1 W m^-2 sr^-1 from every direction), R,G,B "
           "or a number (a uniform radiance), or a lat-long map FILE.hdr or FILE.exr, oriented "
           "as Blender shows it (docs/scene-format.md, environment); `submit` uploads the file "
           "with the scene's")
        ->type_name("white|R,G,B|FILE");
}

absl::Status ResolveSkyFile(const std::string& scene_path, SceneOptions& options) {
    if (options.sky.empty()) return absl::OkStatus();
    absl::StatusOr<SkyOption> sky = ParseSkyOption(options.sky);
    if (!sky.ok()) return sky.status();
    if (sky->file.empty()) return absl::OkStatus();
    namespace fs = std::filesystem;
    std::error_code error;
    if (!fs::is_regular_file(sky->file, error)) {
        return absl::NotFoundError(
            absl::StrCat("--sky ", sky->file, ": no such file (nor white, R,G,B or a number)"));
    }
    // The loader reads files by their names beside the scene, the farm by the names they were
    // uploaded as: one name, relative to the scene's folder, serves both.
    const fs::path folder = fs::absolute(fs::path(scene_path)).parent_path();
    const fs::path name = fs::absolute(fs::path(sky->file)).lexically_relative(folder);
    options.sky = name.empty() ? fs::absolute(fs::path(sky->file)).string() : name.string();
    return absl::OkStatus();
}

void AddSceneFlags(CLI::App* cmd, SceneOptions& options) {
    AddCameraFlag(cmd, options);
    AddResolutionFlag(cmd, options,
                      "image size WxH in pixels, or N for N x N, instead of the scene's (JSON "
                      "resolution or glTF camera)");
    AddFilterFlag(cmd, options);
}

}  // namespace lf
