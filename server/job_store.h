// Jobs as the server records them, behind a small interface: in memory or in SQLite
// (server/sqlite_job_store.h). The scheduler keeps the live task and lease state of running jobs
// itself and writes the job-level record here on every change, and each finished task's result
// with it, so that a restarted server can rebuild its running jobs; finished jobs live only here.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
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
    int tasks_leased = 0;  // leases ever handed out, across server restarts: renders started
    RenderStats stats;
    std::string result_path;  // the EXR, once succeeded
};

class JobStore {
public:
    virtual ~JobStore() = default;
    virtual absl::Status Put(const JobRecord& job) = 0;  // insert or replace, by id
    // Put, together with the encoded TileSums of task `task` of the job, in one write. A record
    // in a final state drops the job's task results.
    virtual absl::Status PutTaskDone(const JobRecord& job, int task, std::string_view result) = 0;
    virtual absl::StatusOr<JobRecord> Get(const std::string& id) const = 0;  // NotFound
    virtual std::vector<JobRecord> List() const = 0;                         // newest first
    // The results PutTaskDone recorded for a job that has not ended, by task index.
    virtual absl::StatusOr<std::map<int, std::string>> TaskResults(const std::string& id) const = 0;
};

// Nothing outlives the process, so there is nothing to recover: task results are not kept.
class InMemoryJobStore : public JobStore {
public:
    absl::Status Put(const JobRecord& job) override;
    absl::Status PutTaskDone(const JobRecord& job, int task, std::string_view result) override {
        return Put(job);
    }
    absl::StatusOr<std::map<int, std::string>> TaskResults(const std::string& id) const override {
        return std::map<int, std::string>{};
    }
    absl::StatusOr<JobRecord> Get(const std::string& id) const override;
    std::vector<JobRecord> List() const override;

private:
    mutable std::mutex mutex_;
    std::map<std::string, JobRecord> jobs_;
};

}  // namespace lf
