#include "lf/core/dir_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"

namespace lf {
namespace {

// The pid the holder wrote, or "unknown" (it may not have written it yet).
std::string HolderPid(int fd) {
    char buffer[32] = {};
    const ssize_t n = ::pread(fd, buffer, sizeof buffer - 1, 0);
    int pid = 0;
    if (n <= 0 || !absl::SimpleAtoi(absl::StripAsciiWhitespace(buffer), &pid)) return "unknown";
    return std::to_string(pid);
}

}  // namespace

absl::StatusOr<std::unique_ptr<DirLock>> DirLock::Acquire(const std::string& dir,
                                                          const DirUse& use) {
    const std::string path = dir + "/lock";
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) return absl::InternalError(absl::StrCat(path, ": ", std::strerror(errno)));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        const int error = errno;
        const std::string pid = error == EWOULDBLOCK ? HolderPid(fd) : "";
        ::close(fd);
        if (error == EWOULDBLOCK) {
            return absl::FailedPreconditionError(absl::StrCat(
                use.folder, " ", dir, " is in use by another ", use.program, " (pid ", pid,
                ", which holds ", path, "); stop it or give this one another ", use.option));
        }
        return absl::InternalError(absl::StrCat(path, ": ", std::strerror(error)));
    }
    const std::string pid = absl::StrCat(::getpid(), "\n");
    if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
        const int error = errno;
        ::close(fd);
        return absl::InternalError(absl::StrCat(path, ": ", std::strerror(error)));
    }
    return std::unique_ptr<DirLock>(new DirLock(fd));
}

DirLock::~DirLock() { ::close(fd_); }

}  // namespace lf
