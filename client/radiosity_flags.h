// The radiosity options `render` and `submit` share, parsed into their plain form, and the
// kernel's options they stand for.
#pragma once

#include <CLI/CLI.hpp>

#include "absl/status/statusor.h"
#include "lf/job/plan.h"
#include "lf/kernels/radiosity.h"

namespace lf {

void AddRadiosityFlags(CLI::App* cmd, RadiositySettings& settings);

// The kernel's options for `settings` (InvalidArgument for an unknown solver or display). Every
// command that solves radiosity in this process starts from these, so its defaults are the
// job model's (lf/job/settings.h), not the kernel's.
absl::StatusOr<RadiosityOptions> RadiosityOptionsOf(const RadiositySettings& settings);

// InvalidArgument naming the first radiosity flag given to `cmd` while `method` is "path",
// which would be silently ignored.
absl::Status CheckRadiosityFlagsApply(const CLI::App& cmd, const std::string& method);

}  // namespace lf
