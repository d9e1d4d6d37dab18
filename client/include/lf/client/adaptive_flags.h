// The adaptive sampling options `render` and `submit` share.
#pragma once

#include <CLI/CLI.hpp>

#include "lf/job/adaptive_plan.h"

namespace lf {

void AddAdaptiveFlags(CLI::App* cmd, AdaptiveSettings& settings);

}  // namespace lf
