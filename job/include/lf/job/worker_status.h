// A worker as the coordinator sees it: what `lightfarm workers` lists (wire: ListWorkers).
#pragma once

#include <cstddef>
#include <string>

#include "absl/time/time.h"

namespace lf {

// The longest worker name (lightfarm-worker --name) the server takes.
constexpr size_t kMaxWorkerNameBytes = 128;

struct WorkerStatus {
    std::string id;       // the worker process' own id (host-pid)
    std::string name;     // lightfarm-worker --name, by default its host name
    std::string address;  // the peer of its last lease request, as gRPC names it
    std::string version;  // its build (lf::kBuildVersion)
    // The task it holds a current lease of: busy; none (job_id empty): idle.
    std::string job_id;
    int task = -1;
    absl::Duration since_seen;  // since its last lease request, heartbeat or result
    bool busy() const { return !job_id.empty(); }
};

}  // namespace lf
