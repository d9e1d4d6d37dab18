#include "lf/kernels/scene_motion.h"

#include <algorithm>

namespace lf {

namespace {

// Whether two poses, at the shutter's opening and closing, give a channel exactly between
// them: a translation whose keys are LINEAR (or STEP) with none inside the shutter moves on a
// straight line at constant speed (or not at all) there. A key inside bends the path; a
// CUBICSPLINE one curves it; rotations, scales and weights are not linear in the vertices.
bool StraightInShutter(const AnimationChannel& c, double open, double close) {
    if (c.path != AnimationChannel::Path::kTranslation) return false;
    if (c.keys.interpolation() == Interpolation::kCubicSpline) return false;
    const std::vector<double>& t = c.keys.times();
    return std::none_of(t.begin(), t.end(), [&](double k) { return k > open && k < close; });
}

}  // namespace

int MotionSteps(const SceneMotion& motion) {
    if (!motion.Blurs()) return 1;
    if (motion.steps > 0) return std::max(motion.steps, 2);
    const auto& channels = motion.animation->channels;
    const bool straight = std::all_of(channels.begin(), channels.end(), [&](const auto& c) {
        return StraightInShutter(c, motion.open, motion.close);
    });
    return straight ? 2 : kCurvedMotionSteps;
}

}  // namespace lf
