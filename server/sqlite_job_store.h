// Jobs and the results of their finished tasks in SQLite, so that a server killed at any point
// and started again on the same data folder loses nothing it acknowledged: every write is one
// transaction committed with WAL and synchronous=FULL before the caller answers anyone.
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "server/job_store.h"

struct sqlite3;

namespace lf {

class SqliteJobStore : public JobStore {
public:
    // Opens or creates the database at `path`.
    static absl::StatusOr<std::unique_ptr<SqliteJobStore>> Open(const std::string& path);
    ~SqliteJobStore() override;

    absl::Status Put(const JobRecord& job) override;
    absl::Status PutTaskDone(const JobRecord& job, int task, std::string_view result) override;
    absl::StatusOr<JobRecord> Get(const std::string& id) const override;
    std::vector<JobRecord> List() const override;
    absl::StatusOr<std::map<int, std::string>> TaskResults(const std::string& id) const override;

private:
    explicit SqliteJobStore(sqlite3* db) : db_(db) {}
    // Runs `body` between BEGIN IMMEDIATE and COMMIT, rolling back when it fails.
    absl::Status Transaction(const std::function<absl::Status()>& body);
    absl::Status PutLocked(const JobRecord& job);

    mutable std::mutex mutex_;
    sqlite3* db_;
};

}  // namespace lf
