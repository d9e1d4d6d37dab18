// --photons, --ppm-radius and --ppm-alpha: progressive photon mapping's settings (`--method
// ppm`), shared by `render` and `submit` so both fill the job model's PhotonSettings alike.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "absl/status/status.h"
#include "lf/job/splat_settings.h"

namespace lf {

void AddPhotonFlags(CLI::App* cmd, PhotonSettings& settings);

// InvalidArgument naming the first photon flag given to `cmd` while `method` is not "ppm" (it
// would be silently ignored).
absl::Status CheckPhotonFlagsApply(const CLI::App& cmd, const std::string& method);

}  // namespace lf
