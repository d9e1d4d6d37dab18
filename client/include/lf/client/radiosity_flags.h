// The radiosity options `render` and `submit` share, parsed into their plain form (the kernel's
// options they stand for: lf::RadiosityOptionsOf, lf/local/method_factory.h).
#pragma once

#include <CLI/CLI.hpp>

#include "absl/status/status.h"
#include "lf/job/plan.h"

namespace lf {

void AddRadiosityFlags(CLI::App* cmd, RadiositySettings& settings);

// InvalidArgument naming the first radiosity flag given to `cmd` while `method` is "path",
// which would be silently ignored.
absl::Status CheckRadiosityFlagsApply(const CLI::App& cmd, const std::string& method);

}  // namespace lf
