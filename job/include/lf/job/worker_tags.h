// Worker tags (pools): lightfarm-worker --tags says what a worker has (gpu, big-memory, ...),
// submit --tags what a job needs. A job is leased only to workers having every one of its
// tags (Flamenco's rule); a job without tags goes to any worker.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace lf {

inline constexpr size_t kMaxTagBytes = 32;
inline constexpr size_t kMaxTags = 32;

// Ok when every tag is [a-z0-9_-]{1,32}, there are at most kMaxTags and none repeats;
// otherwise InvalidArgument naming `what` (e.g. "tags", "--tags") and the tag.
absl::Status CheckTags(const std::vector<std::string>& tags, const std::string& what);

// "a,b" as {"a", "b"} ("" as none), checked as CheckTags does.
absl::StatusOr<std::vector<std::string>> ParseTags(const std::string& list,
                                                   const std::string& what);

// Whether `have` holds every tag of `need`.
bool HasAllTags(const std::vector<std::string>& have, const std::vector<std::string>& need);

// Why a job needing `need` is not leased when no live worker has them all:
// "waiting for a worker with tags gpu,big".
std::string WaitingForTags(const std::vector<std::string>& need);

}  // namespace lf
