#include "lf/client/output_flags.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "lf/core/tone_map.h"

namespace lf {

namespace {

// 2^64 takes a radiance of 1e-19 to white: beyond any scene.
constexpr double kMaxExposure = 64;

std::string Extension(const std::string& path) {
    return absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
}

}  // namespace

void AddOutputFlags(CLI::App* cmd, OutputFlags& flags) {
    cmd->add_option("-o,--output", flags.output,
                    "output file: .exr writes the OpenEXR (float radiance, every channel, the "
                    "header); .png writes only the 8-bit sRGB preview")
        ->required();
    cmd->add_option("--png", flags.png, "also write the sRGB PNG preview, beside an EXR -o");
    cmd->add_option_function<double>(
           "--exposure",
           [&flags](double ev) {
               if (!(std::abs(ev) <= kMaxExposure)) {
                   throw CLI::ValidationError(absl::StrCat("--exposure ", ev, ": expected -",
                                                           kMaxExposure, " to ", kMaxExposure));
               }
               flags.preview.exposure = ev;
           },
           "PNG preview only: scale the radiance by 2^EV before the tone curve (default 0; the "
           "EXR is never scaled)")
        ->type_name("EV");
    cmd->add_option_function<std::string>(
           "--tonemap",
           [&flags](const std::string& name) {
               const std::optional<ToneCurve> curve = ToneCurveFromName(name);
               if (!curve) {
                   throw CLI::ValidationError(
                       absl::StrCat("--tonemap ", name, ": expected clamp or filmic"));
               }
               flags.preview.tone = *curve;
           },
           "PNG preview only: clamp (default; values above 1 clip to white) or filmic (the "
           "ACES filmic curve fitted by Narkowicz 2015: highlights roll off, reaching white at "
           "7.24; 1 maps to 0.80)")
        ->type_name("clamp|filmic");
    cmd->add_option_function<std::string>(
           "--false-color",
           [&flags](const std::string& text) {
               absl::StatusOr<FalseColorSpec> spec = ParseFalseColor(text);
               if (!spec.ok()) throw CLI::ValidationError(std::string(spec.status().message()));
               flags.false_color = *spec;
           },
           "also write a false-colour PNG next to -o (out.exr -> out.falsecolor.png): lux (the "
           "illuminance channel: needs --aov illuminance) or nits (luminance, cd/m^2 = 683 x "
           "Y of the radiance) on a logarithmic viridis scale from MIN to MAX (default: the "
           "1st to 99th percentile, rounded out to powers of ten), with a legend bar, its "
           "decades and the unit under the image")
        ->type_name("lux|nits[:MIN:MAX]");
}

absl::StatusOr<OutputPaths> ResolveOutputPaths(const OutputFlags& flags) {
    OutputPaths paths;
    const std::string ext = Extension(flags.output);
    if (ext == ".exr") {
        paths.exr = flags.output;
    } else if (ext == ".png") {
        paths.png = flags.output;
    } else {
        return absl::InvalidArgumentError(absl::StrCat(
            "-o ", flags.output,
            ": expected a name ending in .exr (the radiance, OpenEXR) or .png (the preview)"));
    }
    if (!flags.png.empty()) {
        if (!paths.png.empty()) {
            return absl::InvalidArgumentError(
                absl::StrCat("--png ", flags.png, ": -o ", flags.output,
                             " already writes the PNG; --png adds a preview beside an EXR"));
        }
        paths.png = flags.png;
    }
    if (flags.false_color) paths.false_color = FalseColorPath(flags.output);
    return paths;
}

std::string OutputNames(const OutputPaths& paths) {
    std::string names;
    for (const std::string* path : {&paths.exr, &paths.png, &paths.false_color}) {
        if (!path->empty()) absl::StrAppend(&names, names.empty() ? "" : " and ", *path);
    }
    return names;
}

absl::Status CheckWritable(const std::string& path) {
    if (path.empty()) return absl::OkStatus();
    const bool existed = std::filesystem::exists(path);
    std::ofstream probe(path, std::ios::app);
    if (!probe) {
        return absl::PermissionDeniedError(path + ": cannot write here: " + std::strerror(errno));
    }
    probe.close();
    if (!existed) std::filesystem::remove(path);
    return absl::OkStatus();
}

}  // namespace lf
