// A worker as the coordinator sees it: what `lightfarm workers` lists (wire: ListWorkers).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "absl/time/time.h"

namespace lf {

// The longest worker name (lightfarm-worker --name) the server takes.
constexpr size_t kMaxWorkerNameBytes = 128;

// What an admin set for a worker (lightfarm workers enable|disable|drain), kept by its name
// across coordinator restarts. Disabled and drained workers lease nothing new; a task they hold
// runs to its end.
enum class WorkerControl { kEnabled, kDisabled, kDrain };
const char* WorkerControlName(WorkerControl control);  // "enabled", "disabled", "drain"

struct WorkerStatus {
    std::string id;       // the worker process' own id (host-pid)
    std::string name;     // lightfarm-worker --name, by default its host name
    std::string address;  // the peer of its last lease request, as gRPC names it
    std::string version;  // its build (lf::kBuildVersion)
    // The task it holds a current lease of: busy; none (job_id empty): idle.
    std::string job_id;
    int task = -1;
    absl::Duration since_seen;      // since its last lease request, heartbeat or result
    std::vector<std::string> tags;  // lightfarm-worker --tags
    WorkerControl control = WorkerControl::kEnabled;
    bool offline = false;  // silent for a lease: listed a while longer, with its last-seen time
    absl::Time last_seen;
    bool busy() const { return !job_id.empty(); }
};

// How `lightfarm workers` shows a worker: offline, disabled, draining (busy) or drained (idle),
// busy or idle.
enum class WorkerState { kIdle, kBusy, kDisabled, kDraining, kDrained, kOffline };
WorkerState StateOf(const WorkerStatus& worker);
const char* WorkerStateName(WorkerState state);  // "idle", "busy", ...

}  // namespace lf
