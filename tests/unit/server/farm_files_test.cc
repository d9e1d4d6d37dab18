// What the farm does with its data folder as a whole: one server per folder, the temporary
// files a killed server left are swept at start, ended jobs past retention are deleted with
// their results at start (and whenever DeleteExpired runs), and blobs go when no job uses them.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "lf/job/digest.h"
#include "lf/server/farm.h"
#include "lf/server/sqlite_job_store.h"
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
        return std::count_if(fs::directory_iterator(dir_ / sub), fs::directory_iterator(),
                             [](const fs::directory_entry& e) { return e.is_regular_file(); });
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

// Sets the file's modification time `ago` before now.
void Age(const fs::path& path, absl::Duration ago) {
    const timespec t = absl::ToTimespec(absl::Now() - ago);
    const timespec times[2] = {t, t};
    ASSERT_EQ(::utimensat(AT_FDCWD, path.c_str(), times, 0), 0) << path;
}

TEST_F(FarmFilesTest, DeletingAJobRemovesTheBlobsNoOtherJobUsesAndNoneUploadedLately) {
    Open().reset();
    auto blob = [&](const std::string& content, absl::Duration age) {
        const std::string hash = Sha256Hex(content);
        std::ofstream(dir_ / "blobs" / hash) << content;
        Age(dir_ / "blobs" / hash, age);
        return BlobRef{"file-" + content, hash, content.size()};
    };
    const BlobRef shared = blob("shared by both jobs", absl::Hours(2));
    const BlobRef own = blob("the deleted job's own", absl::Hours(2));
    const BlobRef kept = blob("the kept job's own", absl::Hours(2));
    const BlobRef orphan = blob("uploaded, never submitted", absl::Hours(2));
    const BlobRef fresh = blob("uploaded a minute ago", absl::Minutes(1));
    {
        std::unique_ptr<SqliteJobStore> store =
            std::move(*SqliteJobStore::Open((dir_ / "jobs.db").string()));
        auto put = [&](const std::string& id, uint64_t seq, std::vector<BlobRef> files) {
            JobRecord job;
            job.id = id;
            job.seq = seq;
            job.state = JobState::kSucceeded;
            job.finished = absl::Now();
            job.spec.scene = files[0];
            job.spec.files.assign(files.begin() + 1, files.end());
            ASSERT_TRUE(store->Put(job).ok());
        };
        put("deleted", 1, {own, shared});
        put("kept", 2, {kept, shared});
    }
    std::unique_ptr<Farm> farm = Open();
    // A queued job, held by the scheduler, whose scene is an old blob.
    std::stringstream scene_text;
    scene_text << std::ifstream(fs::path(LF_TEST_SCENES) / "cornell_box.json").rdbuf();
    const BlobRef queued_scene = blob(scene_text.str(), absl::Hours(2));
    JobSpec spec;
    spec.scene = {"cornell_box.json", queued_scene.hash, queued_scene.size};
    ASSERT_TRUE(farm->Submit(spec).ok());
    // Found stored again by a client that is about to submit.
    const BlobRef found = blob("found stored by MissingBlobs", absl::Hours(2));
    ASSERT_TRUE(farm->blobs().Touch(found.hash));

    ASSERT_TRUE(farm->DeleteJob("deleted").ok());
    EXPECT_FALSE(farm->blobs().Has(own.hash));
    EXPECT_FALSE(farm->blobs().Has(orphan.hash));
    for (const BlobRef& ref : {shared, kept, fresh, queued_scene, found}) {
        EXPECT_TRUE(farm->blobs().Has(ref.hash)) << ref.path;
    }
    // An hour on, the fresh one is no one's either; the others still are someone's.
    ASSERT_TRUE(farm->DeleteExpired(absl::Now() + absl::Minutes(70)).ok());
    EXPECT_FALSE(farm->blobs().Has(fresh.hash));
    EXPECT_FALSE(farm->blobs().Has(found.hash));
    for (const BlobRef& ref : {shared, kept, queued_scene}) {
        EXPECT_TRUE(farm->blobs().Has(ref.hash)) << ref.path;
    }
}

TEST_F(FarmFilesTest, StalePartialUploadsAreRemovedADayAfterTheirLastByte) {
    std::unique_ptr<Farm> farm = Open();
    const std::string content(1000, 'p');
    {
        absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
            farm->StartUpload(Sha256Hex(content), content.size());
        ASSERT_TRUE(upload.ok());
        ASSERT_TRUE((*upload)->Append(content.substr(0, 400)).ok());
    }
    ASSERT_TRUE(farm->DeleteExpired(absl::Now() + absl::Hours(23)).ok());
    EXPECT_EQ(*farm->blobs().UploadOffset(Sha256Hex(content), content.size()), 400u);
    ASSERT_TRUE(farm->DeleteExpired(absl::Now() + kPartialUploadLifetime + absl::Minutes(1)).ok());
    EXPECT_EQ(*farm->blobs().UploadOffset(Sha256Hex(content), content.size()), 0u);
}

}  // namespace
}  // namespace lf
