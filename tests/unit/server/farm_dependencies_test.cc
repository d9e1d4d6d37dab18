// Job dependencies on a real farm (issue 30): the jobs.db keeps what a job runs after, so a
// chain A <- B <- C finishes strictly in order across a coordinator restart, B still waiting
// for A after it.
#include <gtest/gtest.h>

#include <filesystem>

#include "farm_scene.h"
#include "lease_results.h"
#include "lf/core/tile_codec.h"
#include "lf/server/farm.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class FarmDependencies : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_farm_deps");
        Open();
        absl::StatusOr<BlobRef> scene = lf::testing::StoreCornellBox(*farm_, 16);
        ASSERT_TRUE(scene.ok()) << scene.status();
        scene_ = *scene;
    }

    void TearDown() override {
        farm_.reset();
        fs::remove_all(dir_);
    }

    // The coordinator starting (again) on the same data folder.
    void Open() {
        farm_.reset();
        FarmOptions options;
        options.data_dir = dir_.string();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
    }

    // One task: 16x16 in one tile.
    std::string Submit(std::vector<std::string> after = {}) {
        JobSpec spec;
        spec.name = "dep";
        spec.scene = scene_;
        spec.plan.spp = 1;
        spec.plan.tile = 16;
        spec.plan.passes = 1;
        spec.after = std::move(after);
        absl::StatusOr<std::string> id = farm_->Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return id.value_or("");
    }

    // What a worker does: leases a task and sends its result; the job id, or "" for none.
    std::string Work() {
        std::optional<TaskAssignment> lease = farm_->scheduler().LeaseTask("w-1");
        if (!lease) return "";
        const absl::Status done = farm_->Complete(
            lease->lease_id, "w-1", EncodeTileSums(testing::UniformResult(*lease, Rgb(0.5f))));
        EXPECT_TRUE(done.ok()) << done;
        return lease->job_id;
    }

    JobRecord Get(const std::string& id) {
        absl::StatusOr<JobRecord> job = farm_->scheduler().Get(id);
        EXPECT_TRUE(job.ok()) << job.status();
        return job.value_or(JobRecord{});
    }

    fs::path dir_;
    BlobRef scene_;
    std::unique_ptr<Farm> farm_;
};

TEST_F(FarmDependencies, ChainFinishesInOrderAcrossARestart) {
    const std::string a = Submit();
    const std::string b = Submit({a});
    const std::string c = Submit({b});
    Open();
    EXPECT_EQ(Get(b).spec.after, std::vector<std::string>{a}) << "kept in jobs.db";
    EXPECT_EQ(Get(b).waiting_reason, "waiting for " + a + " (queued)");
    EXPECT_EQ(Get(c).waiting_for, std::vector<std::string>{b});
    EXPECT_EQ(Work(), a);
    EXPECT_EQ(Get(a).state, JobState::kSucceeded);
    EXPECT_EQ(Work(), b);
    EXPECT_EQ(Work(), c);
    EXPECT_EQ(Work(), "");
    const JobRecord ra = Get(a), rb = Get(b), rc = Get(c);
    for (const JobRecord* r : {&ra, &rb, &rc}) EXPECT_EQ(r->state, JobState::kSucceeded) << r->id;
    EXPECT_LT(ra.finished, rb.started);
    EXPECT_LT(rb.finished, rc.started);
}

// Deleting a dependency that ended: a dependent it failed stays failed with the reason, and one
// it released renders, across a restart too (the delete is no failure).
TEST_F(FarmDependencies, DeletingAnEndedDependencyFailsNothing) {
    const std::string a = Submit();
    const std::string b = Submit({a});
    ASSERT_TRUE(farm_->scheduler().Cancel(a).ok());
    ASSERT_TRUE(farm_->DeleteJob(a).ok());
    EXPECT_EQ(Get(b).state, JobState::kFailed);
    EXPECT_EQ(Get(b).error, "dependency " + a + " was cancelled");

    const std::string c = Submit();
    EXPECT_EQ(Work(), c);
    const std::string d = Submit({c});
    ASSERT_TRUE(farm_->DeleteJob(c).ok());
    Open();
    EXPECT_EQ(Get(d).state, JobState::kQueued);
    EXPECT_EQ(Work(), d);
    EXPECT_EQ(Get(d).state, JobState::kSucceeded);
}

}  // namespace
}  // namespace lf
