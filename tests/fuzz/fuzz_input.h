// Helpers for the fuzz targets: the input's first byte picks a variant, the rest is the data.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "spdlog/spdlog.h"

namespace lf::fuzz {

// The loaders' warnings would be most of the time spent: off, once.
inline void Quiet() {
    static const bool quiet = (spdlog::set_level(spdlog::level::off), true);
    (void)quiet;
}

struct Input {
    uint8_t choice = 0;
    std::string bytes;
};

inline Input Split(const uint8_t* data, size_t size) {
    if (size == 0) return {};
    return {data[0], std::string(reinterpret_cast<const char*>(data + 1), size - 1)};
}

// A reader for the files a scene names: none is there, as on a farm with no uploads.
inline absl::StatusOr<std::string> NoFile(const std::string& name) {
    return absl::NotFoundError(name + ": no such file");
}

}  // namespace lf::fuzz
