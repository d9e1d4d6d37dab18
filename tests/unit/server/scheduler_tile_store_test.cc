// The scheduler with each job's tiles in files, as the coordinator runs it: snapshots have the
// bits of in-memory tiles, a restarted scheduler rebuilds the files from the recorded results,
// and submissions beyond --max-active-jobs are refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>

#include "lf/server/scheduler.h"
#include "lf/server/sqlite_job_store.h"
#include "test_dir.h"
#include "test_job_store.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class SchedulerTileStoreTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_sched_tiles");
        fs::create_directories(dir_ / "tiles");
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::unique_ptr<SqliteJobStore> OpenStore() { return lf::testing::OpenJobStore(dir_); }

    SchedulerOptions InFiles() const {
        SchedulerOptions options;
        options.tile_stores = [dir = (dir_ / "tiles").string()](std::vector<PixelRect> tiles,
                                                                uint32_t aovs) {
            return MakeFileTileStore(dir, std::move(tiles), aovs);
        };
        return options;
    }

    // A 16x16 image in 8x8 tiles, 4 spp in 2 passes: 8 tasks; adaptive when `target` > 0.
    static JobSpec Spec(double target = 0) {
        JobSpec spec;
        spec.name = "test";
        spec.plan = {16, 16, 4, 8, 2};
        if (target > 0) spec.adaptive = {.target_error = target, .time_limit = 0, .max_spp = 64};
        return spec;
    }

    // Pixels that depend on the task and the pixel, so a wrong merge shows in the image.
    static TileSums Result(const TaskAssignment& lease) {
        TileSums sums(lease.task.rect);
        for (size_t i = 0; i < sums.pixels.size(); ++i) {
            for (uint64_t s = lease.task.sample_begin; s < lease.task.sample_end; ++s) {
                sums.pixels[i].Add(
                    s, Rgb(0.1f * float(lease.task.index + 1) + float(i % 7), float(s % 3), 0.25f));
            }
        }
        return sums;
    }

    // Completes `count` tasks (all when negative).
    static void Complete(Scheduler& scheduler, int count = -1) {
        for (int n = 0; n != count; ++n) {
            std::optional<TaskAssignment> lease = scheduler.LeaseTask("w");
            if (!lease) return;
            ASSERT_TRUE(scheduler.Complete(lease->lease_id, "w", Result(*lease)).ok());
        }
    }

    static Image Snapshot(const Scheduler& scheduler, const std::string& id) {
        absl::StatusOr<Scheduler::JobImage> snapshot = scheduler.Snapshot(id);
        EXPECT_TRUE(snapshot.ok()) << snapshot.status();
        return snapshot.ok() ? snapshot->image : Image();
    }

    static void ExpectSameBits(const Image& a, const Image& b) {
        ASSERT_EQ(a.channels().size(), b.channels().size());
        for (const auto& [name, data] : a.channels()) {
            const std::vector<float>* other = b.FindChannel(name);
            ASSERT_NE(other, nullptr) << name;
            EXPECT_EQ(0, std::memcmp(data.data(), other->data(), data.size() * sizeof(float)))
                << name;
        }
    }

    fs::path dir_;
};

TEST_F(SchedulerTileStoreTest, FileTilesGiveTheBitsOfMemoryTilesPlainAndAdaptive) {
    for (double target : {0.0, 0.02}) {
        InMemoryJobStore memory_store, file_store;
        Scheduler memory(SchedulerOptions(), memory_store);
        Scheduler file(InFiles(), file_store);
        absl::StatusOr<std::string> a = memory.Submit(Spec(target)), b = file.Submit(Spec(target));
        ASSERT_TRUE(a.ok() && b.ok());
        Complete(memory, 3);
        Complete(file, 3);
        ExpectSameBits(Snapshot(file, *b), Snapshot(memory, *a));  // a preview
        Complete(memory);
        Complete(file);
        ExpectSameBits(Snapshot(file, *b), Snapshot(memory, *a));
        absl::StatusOr<Scheduler::JobImage> with_report = file.Snapshot(*b);
        ASSERT_TRUE(with_report.ok());
        EXPECT_EQ(with_report->adaptive.has_value(), target > 0);
    }
}

TEST_F(SchedulerTileStoreTest, RestartRebuildsTheTileFilesFromTheRecordedResults) {
    std::string id;
    Image before;
    {
        std::unique_ptr<SqliteJobStore> store = OpenStore();
        Scheduler scheduler(InFiles(), *store);
        absl::StatusOr<std::string> submitted = scheduler.Submit(Spec());
        ASSERT_TRUE(submitted.ok());
        id = *submitted;
        Complete(scheduler, 5);
        before = Snapshot(scheduler, id);
    }
    std::unique_ptr<SqliteJobStore> store = OpenStore();
    Scheduler scheduler(InFiles(), *store);
    ASSERT_TRUE(scheduler.Recover().ok());
    ExpectSameBits(Snapshot(scheduler, id), before);
    EXPECT_TRUE(fs::is_empty(dir_ / "tiles"));  // the files are unlinked once open
}

TEST_F(SchedulerTileStoreTest, SubmissionBeyondMaxActiveJobsIsRefusedNamingTheFlag) {
    InMemoryJobStore store;
    SchedulerOptions options = InFiles();
    options.max_active_jobs = 2;
    Scheduler scheduler(options, store);
    ASSERT_TRUE(scheduler.Submit(Spec()).ok());
    absl::StatusOr<std::string> second = scheduler.Submit(Spec());
    ASSERT_TRUE(second.ok());
    const absl::StatusOr<std::string> third = scheduler.Submit(Spec());
    EXPECT_EQ(third.status().code(), absl::StatusCode::kResourceExhausted);
    EXPECT_NE(third.status().message().find("--max-active-jobs"), std::string_view::npos)
        << third.status();
    // A job that ends makes room.
    ASSERT_TRUE(scheduler.Cancel(*second).ok());
    EXPECT_TRUE(scheduler.Submit(Spec()).ok());
}

}  // namespace
}  // namespace lf
