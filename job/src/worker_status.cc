#include "lf/job/worker_status.h"

namespace lf {

const char* WorkerControlName(WorkerControl control) {
    switch (control) {
        case WorkerControl::kEnabled:
            return "enabled";
        case WorkerControl::kDisabled:
            return "disabled";
        case WorkerControl::kDrain:
            return "drain";
    }
    return "?";
}

WorkerState StateOf(const WorkerStatus& worker) {
    if (worker.offline) return WorkerState::kOffline;
    switch (worker.control) {
        case WorkerControl::kDisabled:
            return WorkerState::kDisabled;
        case WorkerControl::kDrain:
            return worker.busy() ? WorkerState::kDraining : WorkerState::kDrained;
        case WorkerControl::kEnabled:
            break;
    }
    return worker.busy() ? WorkerState::kBusy : WorkerState::kIdle;
}

const char* WorkerStateName(WorkerState state) {
    switch (state) {
        case WorkerState::kIdle:
            return "idle";
        case WorkerState::kBusy:
            return "busy";
        case WorkerState::kDisabled:
            return "disabled";
        case WorkerState::kDraining:
            return "draining";
        case WorkerState::kDrained:
            return "drained";
        case WorkerState::kOffline:
            return "offline";
    }
    return "?";
}

}  // namespace lf
