#include "server/render_metadata.h"

#include "lf/version.h"

namespace lf {

ExrAttributes DescribeRender(const RenderMetadata& m) {
    return {
        {"lightfarm.version", std::string(kVersion)},
        {"lightfarm.sceneHash", m.scene_hash},
        {"lightfarm.method", m.method},
        {"lightfarm.spp", int(m.spp)},
        {"lightfarm.seed", std::to_string(m.seed)},
        {"lightfarm.maxDepth", m.max_depth},
        {"lightfarm.seconds", m.seconds},
        {"lightfarm.invalidSamples", std::to_string(m.stats.invalid_samples)},
        {"lightfarm.rays", std::to_string(m.stats.rays)},
        {"lightfarm.channels",
         std::string("R,G,B: mean radiance W m^-2 sr^-1 (box filter); A.*, B.*: means of the "
                     "even and odd samples; spp: samples per pixel")},
    };
}

}  // namespace lf
