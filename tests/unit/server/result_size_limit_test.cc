// The largest task result the wire takes (lf::kMaxTaskResultBytes) must also be one the job store
// can record: a splat task's result is stored whole (its LFFR record: header, camera sums,
// splats) as one SQLite blob, and a blob above SQLite's length limit fails the write after the
// merge, which fails the job (Scheduler::Complete) instead of refusing the task on the worker.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "lf/job/splat_settings.h"

namespace lf {
namespace {

TEST(ResultSizeLimitTest, LargestResultFitsInOneSqliteBlob) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(":memory:", &db), SQLITE_OK);
    // -1 reads the limit of the SQLite this server links (1e9 bytes unless built otherwise).
    const int64_t limit = sqlite3_limit(db, SQLITE_LIMIT_LENGTH, -1);
    sqlite3_close(db);
    // The worker sends up to kMaxTaskResultBytes - 4096 bytes of sums and splats; the LFFR
    // header adds 16 (job/src/splat_result_codec.cc).
    EXPECT_LE(int64_t(kMaxTaskResultBytes) + 16, limit);
}

}  // namespace
}  // namespace lf
