// What moves during a frame's shutter, for motion blur: the scene's animation and the shutter's
// interval. EmbreeScene::Build poses the scene at `steps` evenly spaced times over it; a ray's
// time (Ray::time, 0 at the opening, 1 at the closing) then places everything that moves.
#pragma once

#include "lf/core/scene_animation.h"

namespace lf {

struct SceneMotion {
    const SceneAnimation* animation = nullptr;  // null: nothing moves
    double open = 0, close = 0;                 // the shutter, in seconds (lf::ShutterOf)
    // Poses over the shutter, at least 2; 0: MotionSteps chooses.
    int steps = 0;

    // Whether the shutter is open for a while and something moves in it: else the scene
    // renders as the instant it was posed at, exactly as a still.
    bool Blurs() const { return animation && close > open && animation->Moves(); }
};

// Embree interpolates linearly between poses. 2 when every channel is a translation on a
// straight line at constant speed over the shutter (LINEAR or STEP keys, none inside it), so the
// two poses are exact; else kCurvedMotionSteps, enough for rotations, deformations, keys inside
// the shutter and CUBICSPLINE paths: an object turning a quarter turn in the shutter strays from
// its arc by r (1 - cos(pi / 32)), 0.5% of its radius. motion.steps when given. 1 when motion
// does not blur.
inline constexpr int kCurvedMotionSteps = 9;
int MotionSteps(const SceneMotion& motion);

}  // namespace lf
