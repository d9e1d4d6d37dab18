// The worker controls an admin set (lightfarm workers disable|enable|drain), by worker name, in
// the data folder's workers.db: a disabled worker stays disabled across coordinator restarts.
// Enabled workers have no row.
#pragma once

#include <sqlite3.h>

#include <map>
#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "lf/job/worker_status.h"

namespace lf {

class WorkerStateStore {
  public:
    // Creates the file and its table when missing (a data folder from before worker control).
    static absl::StatusOr<std::unique_ptr<WorkerStateStore>> Open(const std::string& path);
    ~WorkerStateStore();
    WorkerStateStore(const WorkerStateStore&) = delete;
    WorkerStateStore& operator=(const WorkerStateStore&) = delete;

    // Durable once it returns.
    absl::Status Put(const std::string& name, WorkerControl control);
    // Every control set, by name; a row this build does not know is an error naming it.
    absl::StatusOr<std::map<std::string, WorkerControl>> List();

  private:
    WorkerStateStore(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
    sqlite3* db_;
    const std::string path_;
};

}  // namespace lf
