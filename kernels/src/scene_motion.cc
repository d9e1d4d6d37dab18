#include "lf/kernels/scene_motion.h"

#include <algorithm>

namespace lf {

int MotionSteps(const SceneMotion& motion) {
    if (!motion.Blurs()) return 1;
    if (motion.steps > 0) return std::max(motion.steps, 2);
    const auto& channels = motion.animation->channels;
    const bool translations_only = std::all_of(channels.begin(), channels.end(), [](const auto& c) {
        return c.path == AnimationChannel::Path::kTranslation;
    });
    return translations_only ? 2 : kCurvedMotionSteps;
}

}  // namespace lf
