// The --method flag of `render`, `plan` and `submit`: a method of lf/job/method_registry.h, or
// (locally) auto, which lf::ChooseAutomatically resolves per scene.
#pragma once

#include <optional>
#include <string>

#include "lf/job/method_registry.h"

namespace lf {

// The CLI's check of a --method flag: "" when the job model accepts `method` (or it is "auto"
// and allow_auto), else the message listing the methods.
std::string MethodFlagError(const std::string& method, bool allow_auto);

// The method of a flag MethodFlagError accepted with allow_auto; nullopt for auto.
std::optional<Method> MethodOfFlag(const std::string& method);

}  // namespace lf
