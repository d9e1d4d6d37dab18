// -o, --png, --exposure, --tonemap and --false-color: which image files `render` and `fetch`
// write (an OpenEXR of the radiance, an sRGB PNG preview, or both, and a false-colour PNG of lux
// or nits) and how the preview is made from the radiance.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/core/false_color.h"
#include "lf/core/image_io.h"

namespace lf {

struct OutputFlags {
    std::string output;  // -o: .exr (the radiance) or .png (the preview alone)
    std::string png;     // --png: a preview beside an EXR
    PngOptions preview;  // --exposure, --tonemap
    std::optional<FalseColorSpec> false_color;  // --false-color
};

// The files to write; "" for none.
struct OutputPaths {
    std::string exr, png;
    std::string false_color;  // FalseColorPath of -o with --false-color
};

// -o (required), --png, --exposure, --tonemap and --false-color into `flags`.
void AddOutputFlags(CLI::App* cmd, OutputFlags& flags);

// What -o and --png ask for. InvalidArgument, naming the flag, for -o ending in neither .exr
// nor .png (any case), or --png beside a PNG -o.
absl::StatusOr<OutputPaths> ResolveOutputPaths(const OutputFlags& flags);

// "out.exr", "out.png" or "out.exr and out.png", for a command's last line.
std::string OutputNames(const OutputPaths& paths);

// Ok if a file can be created (or appended to) at `path`, leaving no trace; "" is ok. Checked
// before rendering or downloading, so that a typo in a path does not lose the work.
absl::Status CheckWritable(const std::string& path);

}  // namespace lf
