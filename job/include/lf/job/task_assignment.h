// One leased task as the coordinator hands it out and a worker runs it: which job, which
// pixels and samples (or which patch-group chunk of a radiosity sweep), and the job's settings.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/time/time.h"
#include "lf/job/job_spec.h"
#include "lf/job/plan.h"

namespace lf {

struct TaskAssignment {
    std::string lease_id;
    std::string job_id;
    RenderTask task;  // a tile's rectangle and samples; for a sweep task only its index
    JobSpec spec;
    // Radiosity jobs solved in sweeps (SolvedInSweeps): a patch-group task of sweep `sweep`
    // (>= 0) sweeps `chunks` (one in sweep 0; later, every chunk the worker holds) and reads the
    // gathered irradiance of the sweep before from the blob `radiosity_hash` ("" in sweep 0:
    // zero, B = E); a display tile (sweep -1) reads the solution from it.
    int sweep = -1;
    std::vector<int> chunks;
    std::string radiosity_hash;
    // A sweep's input itself when it travels with the lease (kMaxInlineRadiosityBytes at most):
    // then the blob `radiosity_hash` is not stored. Null: the worker fetches the blob.
    std::shared_ptr<const std::string> radiosity_input;
    // Splatting methods (UsesSplatPlan(spec.method)): the task's light paths or photon passes
    // [path_begin, path_end) over the whole frame (lf::SplatTask); `task` holds its camera part.
    uint64_t path_begin = 0, path_end = 0;
    // A shot's task (JobSpec::shot.frames, lf/job/shot_execution.h): the frame it renders, the
    // scene posed at its time; nullopt for a still.
    std::optional<int> frame;
    // A chunk of a shot (shot.chunk > 1): every task of several frames, run in this order by one
    // worker; `task`, `frame` and the path range above are then unused.
    struct Part {
        int frame = 0;
        RenderTask task;
        uint64_t path_begin = 0, path_end = 0;
    };
    std::vector<Part> parts;
    absl::Duration heartbeat_interval = absl::Milliseconds(300);
    absl::Duration lease = absl::Seconds(10);
};

}  // namespace lf
