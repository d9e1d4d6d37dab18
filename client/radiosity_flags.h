// The radiosity options `render` and `submit` share, parsed into their plain form.
#pragma once

#include <CLI/CLI.hpp>

#include "lf/job/plan.h"

namespace lf {

void AddRadiosityFlags(CLI::App* cmd, RadiositySettings& settings);

}  // namespace lf
