#pragma once

#include <string>

#include "absl/status/statusor.h"

namespace lf {

// The whole file as bytes; NotFound if it does not exist, InvalidArgument if unreadable.
absl::StatusOr<std::string> ReadFile(const std::string& path);

}  // namespace lf
