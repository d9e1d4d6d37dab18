// One process per folder: an exclusive flock on DIR/lock, held while the object lives (the
// kernel drops it when the process dies, so a crash leaves no stale lock behind). The holder
// writes its pid into the file, so that the one refused can say who holds the folder. A server's
// data folder and a worker's cache folder are held this way.
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace lf {

// How a refusal names the folder: "data folder", the program that holds it
// ("lightfarm-server") and the option that picks another one ("--data-dir").
struct DirUse {
    const char* folder;
    const char* program;
    const char* option;
};

class DirLock {
  public:
    // FailedPrecondition, naming the folder and the holder's pid, when another process holds it.
    static absl::StatusOr<std::unique_ptr<DirLock>> Acquire(const std::string& dir,
                                                            const DirUse& use);
    ~DirLock();
    DirLock(const DirLock&) = delete;
    DirLock& operator=(const DirLock&) = delete;

  private:
    explicit DirLock(int fd) : fd_(fd) {}
    int fd_;
};

}  // namespace lf
