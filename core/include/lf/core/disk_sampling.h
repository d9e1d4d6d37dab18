// Points on the unit disk from uniform numbers: lens samples for the camera, and Malley's
// cosine-weighted hemisphere for the BSDFs.
#pragma once

#include "lf/core/vec.h"

namespace lf {

// Shirley and Chiu's concentric map: uniform on the unit disk with little distortion, and
// continuous, so stratified u stays stratified on the disk.
Vec2 SampleUniformDiskConcentric(const Vec2& u);

}  // namespace lf
