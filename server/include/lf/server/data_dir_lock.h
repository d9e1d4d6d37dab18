// One server per data folder: an exclusive flock on DATA_DIR/lock, held while the object lives
// (the kernel drops it when the process dies, so a crash leaves no stale lock behind).
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace lf {

class DataDirLock {
  public:
    // FailedPrecondition, naming the folder, when another process holds it.
    static absl::StatusOr<std::unique_ptr<DataDirLock>> Acquire(const std::string& dir);
    ~DataDirLock();
    DataDirLock(const DataDirLock&) = delete;
    DataDirLock& operator=(const DataDirLock&) = delete;

  private:
    explicit DataDirLock(int fd) : fd_(fd) {}
    int fd_;
};

}  // namespace lf
