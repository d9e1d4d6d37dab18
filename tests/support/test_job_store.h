// The coordinator's SQLite job store in a test's folder.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>

#include "lf/server/sqlite_job_store.h"

namespace lf::testing {

// The store `dir`/jobs.db, created on first use; a failure to open fails the test and returns
// null.
inline std::unique_ptr<SqliteJobStore> OpenJobStore(const std::filesystem::path& dir) {
    absl::StatusOr<std::unique_ptr<SqliteJobStore>> store =
        SqliteJobStore::Open((dir / "jobs.db").string());
    EXPECT_TRUE(store.ok()) << store.status();
    return store.ok() ? std::move(*store) : nullptr;
}

}  // namespace lf::testing
