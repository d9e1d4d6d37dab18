// Jobs as the server records them, behind a small interface: in memory now, SQLite next. The
// scheduler keeps the live task and lease state of running jobs itself and writes the job-level
// record here on every change; finished jobs live only here.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/core/film.h"
#include "server/plan.h"
#include "server/scene_files.h"

namespace lf {

struct JobSpec {
    std::string name;
    BlobRef scene;               // the scene JSON
    std::vector<BlobRef> files;  // the files it names
    RenderPlanSettings plan;     // width and height come from the scene
    uint64_t seed = 0;
    int max_depth = -1;
    int priority = 0;        // higher first
    std::string scene_hash;  // the loader's content hash, for the EXR header
};

enum class JobState { kQueued, kRunning, kSucceeded, kFailed, kCancelled };
const char* JobStateName(JobState state);
inline bool IsFinal(JobState s) { return s != JobState::kQueued && s != JobState::kRunning; }

struct JobRecord {
    std::string id;
    uint64_t seq = 0;  // submission order
    JobSpec spec;
    JobState state = JobState::kQueued;
    std::string error;
    absl::Time submitted, started = absl::InfinitePast(), finished = absl::InfinitePast();
    int tasks_total = 0, tasks_done = 0, tasks_running = 0, retries = 0;
    RenderStats stats;
    std::string result_path;  // the EXR, once succeeded
};

class JobStore {
public:
    virtual ~JobStore() = default;
    virtual absl::Status Put(const JobRecord& job) = 0;  // insert or replace, by id
    virtual absl::StatusOr<JobRecord> Get(const std::string& id) const = 0;  // NotFound
    virtual std::vector<JobRecord> List() const = 0;                         // newest first
};

class InMemoryJobStore : public JobStore {
public:
    absl::Status Put(const JobRecord& job) override;
    absl::StatusOr<JobRecord> Get(const std::string& id) const override;
    std::vector<JobRecord> List() const override;

private:
    mutable std::mutex mutex_;
    std::map<std::string, JobRecord> jobs_;
};

}  // namespace lf
