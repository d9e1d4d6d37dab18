// What a job asks for: the scene, as blobs, and every setting of its render. The same struct
// travels from the client (`submit`) through the coordinator to the workers, and local mode
// (`render`) fills it from the same flags, so both see the same defaults (settings.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lf/job/adaptive_plan.h"
#include "lf/job/plan.h"
#include "lf/job/scene_files.h"
#include "lf/job/settings.h"

namespace lf {

struct JobSpec {
    std::string name;
    BlobRef scene;               // the scene JSON
    std::vector<BlobRef> files;  // the files it names
    RenderPlanSettings plan;     // width and height come from the scene
    uint64_t seed = defaults::kSeed;
    int max_depth = defaults::kMaxDepth;
    std::string method = defaults::kMethod;  // or "radiosity"
    RadiositySettings radiosity;
    AdaptiveSettings adaptive;  // IsAdaptive: plan.spp is the first pass, plan.passes unused
    int priority = 0;           // higher first
    std::string scene_hash;     // the loader's content hash, for the EXR header
    std::string request_id;     // the client's, for idempotent retries; "" for none
};

// Radiosity jobs the farm solves in patch-group tasks per sweep, rather than on every worker.
// Not adaptive ones: their passes are appended to the tasks where the sweeps would go.
inline bool SolvedInSweeps(const JobSpec& spec) {
    return spec.method == "radiosity" && spec.radiosity.solver == "jacobi" &&
           !IsAdaptive(spec.adaptive);
}

}  // namespace lf
