// One direction sampled from a BSDF (lf/kernels/bsdf.h), with what a path needs to carry on.
#pragma once

#include "lf/core/rgb.h"
#include "lf/core/vec.h"

namespace lf {

struct BsdfSample {
    Rgb f;  // BSDF value for (wo, wi); for delta lobes the value that, times |cos|/pdf,
            // gives the throughput weight
    Vec3 wi;
    float pdf = 0;  // solid angle density; for delta lobes the discrete probability of the lobe
    bool delta = false;
    // IOR on wi's side over the IOR on wo's side when wi crossed a refracting interface, else 1:
    // radiance carried across it scales by 1 / eta^2 (already in f), which Russian roulette
    // should not mistake for absorption.
    float eta = 1;
};

}  // namespace lf
