// A made-up result for a leased tile task: every sample of every pixel the same radiance, so
// scheduler and store tests can complete tasks without rendering.
#pragma once

#include "lf/job/merge.h"
#include "lf/job/task_assignment.h"

namespace lf::testing {

inline TileSums UniformResult(const TaskAssignment& lease, Rgb radiance) {
    TileSums sums(lease.task.rect);
    for (PixelSums& p : sums.pixels) {
        for (uint64_t s = lease.task.sample_begin; s < lease.task.sample_end; ++s) {
            p.Add(s, radiance);
        }
    }
    return sums;
}

}  // namespace lf::testing
