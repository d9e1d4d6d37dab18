// The dashboard's files (server/web/), embedded in the server at build time by
// cmake/embed_files.cmake: the server needs nothing beside its binary, and no internet.
#pragma once

#include <span>
#include <string_view>

namespace lf {

struct WebAsset {
    std::string_view name;  // the path under server/web/
    std::string_view content;
};

std::span<const WebAsset> WebAssets();

}  // namespace lf
