// The EXR header attributes that say how an image was made, the same for `lightfarm render`
// and the farm.
#pragma once

#include <cstdint>
#include <string>

#include "lf/core/film.h"
#include "lf/core/image_io.h"

namespace lf {

struct RenderMetadata {
    std::string scene_hash;
    std::string method;  // "path"
    uint64_t spp = 0;
    uint64_t seed = 0;
    int max_depth = -1;
    double seconds = 0;
    RenderStats stats;
};

ExrAttributes DescribeRender(const RenderMetadata& metadata);

}  // namespace lf
