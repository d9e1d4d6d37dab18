#include "lf/core/file_util.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"

namespace lf {

absl::StatusOr<std::string> ReadFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        const std::string message = absl::StrCat(path, ": cannot open: ", std::strerror(errno));
        if (!std::filesystem::exists(path)) return absl::NotFoundError(message);
        return absl::InvalidArgumentError(message);
    }
    std::ostringstream bytes;
    bytes << in.rdbuf();
    if (in.bad()) return absl::InvalidArgumentError(absl::StrCat(path, ": read error"));
    return std::move(bytes).str();
}

}  // namespace lf
