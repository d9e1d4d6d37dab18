// What the farm does with its data folder as a whole: one server per folder, the temporary
// files a killed server left are swept at start, and ended jobs past retention are deleted with
// their results at start (and whenever DeleteExpired runs).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "server/farm.h"
#include "server/sqlite_job_store.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class FarmFilesTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_farmfiles");
        options_.data_dir = dir_.string();
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::unique_ptr<Farm> Open() {
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options_);
        EXPECT_TRUE(farm.ok()) << farm.status();
        return farm.ok() ? std::move(*farm) : nullptr;
    }

    fs::path dir_;
    FarmOptions options_;
};

TEST_F(FarmFilesTest, SecondFarmOnTheSameDataDirIsRefusedWhileTheFirstRuns) {
    std::unique_ptr<Farm> first = Open();
    const absl::StatusOr<std::unique_ptr<Farm>> second = Farm::Open(options_);
    ASSERT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(second.status().message().find(dir_.string()), std::string_view::npos);
    EXPECT_NE(second.status().message().find("another lightfarm-server"), std::string_view::npos)
        << second.status();
    first.reset();
    EXPECT_TRUE(Open()) << "the lock goes with the farm";
}

TEST_F(FarmFilesTest, TemporaryFilesOfAKilledServerAreSweptAtStart) {
    Open().reset();
    std::ofstream(dir_ / "blobs" / ".upload-abc-1-1") << "partial upload";
    fs::create_directories(dir_ / "scratch" / "submit-1-1");
    std::ofstream(dir_ / "scratch" / "submit-1-1" / "mesh.obj") << "v 0 0 0";
    std::ofstream(dir_ / "previews" / "job-1.exr") << "preview";
    std::ofstream(dir_ / "results" / "job-1.exr.tmp-1-1") << "half a result";
    std::ofstream(dir_ / "results" / "job-2.exr") << "a result";
    std::unique_ptr<Farm> farm = Open();
    auto entries = [&](const char* sub) {
        return std::distance(fs::directory_iterator(dir_ / sub), fs::directory_iterator());
    };
    EXPECT_EQ(entries("blobs"), 0);
    EXPECT_EQ(entries("scratch"), 0);
    EXPECT_EQ(entries("previews"), 0);
    EXPECT_EQ(entries("results"), 1);
    EXPECT_TRUE(fs::exists(dir_ / "results" / "job-2.exr"));
}

TEST_F(FarmFilesTest, JobsEndedLongerAgoThanRetentionAreDeletedAtStart) {
    Open().reset();
    const absl::Time now = absl::Now();
    {
        std::unique_ptr<SqliteJobStore> store =
            std::move(*SqliteJobStore::Open((dir_ / "jobs.db").string()));
        auto put = [&](const std::string& id, uint64_t seq, JobState state, absl::Duration ago) {
            JobRecord job;
            job.id = id;
            job.seq = seq;
            job.state = state;
            job.finished = now - ago;
            job.result_path = (dir_ / "results" / (id + ".exr")).string();
            ASSERT_TRUE(store->Put(job).ok());
            std::ofstream(job.result_path) << "exr";
        };
        put("old", 1, JobState::kSucceeded, absl::Hours(24 * 40));
        put("recent", 2, JobState::kSucceeded, absl::Hours(24 * 2));
    }
    options_.retention = absl::Hours(24 * 30);
    std::unique_ptr<Farm> farm = Open();
    EXPECT_EQ(farm->scheduler().Get("old").status().code(), absl::StatusCode::kNotFound);
    EXPECT_FALSE(fs::exists(dir_ / "results" / "old.exr"));
    EXPECT_TRUE(farm->scheduler().Get("recent").ok());
    EXPECT_TRUE(fs::exists(dir_ / "results" / "recent.exr"));
    // And later, when the recent one's time has come.
    EXPECT_EQ(*farm->DeleteExpired(now + absl::Hours(24 * 29)), 1);
    EXPECT_FALSE(fs::exists(dir_ / "results" / "recent.exr"));
    EXPECT_EQ(*farm->DeleteExpired(now + absl::Hours(24 * 365)), 0);
}

TEST_F(FarmFilesTest, ZeroRetentionKeepsEverything) {
    Open().reset();
    JobRecord job;
    job.id = "ancient";
    job.state = JobState::kFailed;
    job.finished = absl::UnixEpoch();
    ASSERT_TRUE((*SqliteJobStore::Open((dir_ / "jobs.db").string()))->Put(job).ok());
    options_.retention = absl::ZeroDuration();
    std::unique_ptr<Farm> farm = Open();
    EXPECT_EQ(*farm->DeleteExpired(absl::Now() + absl::Hours(24 * 365 * 100)), 0);
    EXPECT_TRUE(farm->scheduler().Get("ancient").ok());
}

}  // namespace
}  // namespace lf
