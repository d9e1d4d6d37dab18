// Worker pools (issue 30): a job with tags is leased only to workers having every one of them,
// a job without tags to any worker; max_workers caps the distinct workers holding its leases;
// a job no live worker can take says why in its record.
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "lease_results.h"
#include "lf/job/worker_tags.h"
#include "lf/server/scheduler.h"
#include "lf/server/worker_registry.h"
#include "lf/wire/stored_job.h"

namespace lf {
namespace {

class WorkerPoolsTest : public ::testing::Test {
  protected:
    WorkerPoolsTest() : scheduler_(SchedulerOptions{}, store_, [this] { return now_; }) {}

    // A 16x16 image in 8x8 tiles, 4 spp in 2 passes: 8 tasks.
    std::string Submit(std::vector<std::string> tags, int max_workers = 0) {
        JobSpec spec;
        spec.name = "pools";
        spec.plan = {16, 16, 4, 8, 2};
        spec.tags = std::move(tags);
        spec.max_workers = max_workers;
        absl::StatusOr<std::string> id = scheduler_.Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        now_ += absl::Milliseconds(1);
        return *id;
    }

    std::optional<TaskAssignment> Lease(const std::string& worker,
                                        std::vector<std::string> tags = {}) {
        const WorkerDescription about{.name = worker, .tags = std::move(tags)};
        return scheduler_.LeaseTask(worker, absl::InfinitePast(), &about);
    }

    absl::Time now_ = absl::FromUnixSeconds(1'000'000);
    InMemoryJobStore store_;
    Scheduler scheduler_;
};

TEST_F(WorkerPoolsTest, TaggedJobGoesOnlyToWorkersWithEveryTag) {
    const std::string gpu = Submit({"gpu", "big"});
    EXPECT_FALSE(Lease("plain").has_value());
    EXPECT_FALSE(Lease("half", {"gpu"}).has_value());
    const std::optional<TaskAssignment> lease = Lease("full", {"big", "gpu", "extra"});
    ASSERT_TRUE(lease.has_value());
    EXPECT_EQ(lease->job_id, gpu);
}

TEST_F(WorkerPoolsTest, UntaggedJobGoesToAnyWorkerAfterTaggedOnesItCannotTake) {
    Submit({"gpu"});
    const std::string any = Submit({});
    const std::optional<TaskAssignment> plain = Lease("plain");
    ASSERT_TRUE(plain.has_value());
    EXPECT_EQ(plain->job_id, any);
    const std::optional<TaskAssignment> tagged = Lease("tagged", {"gpu"});
    ASSERT_TRUE(tagged.has_value());
    EXPECT_NE(tagged->job_id, any) << "the older tagged job first, as for any job";
}

TEST_F(WorkerPoolsTest, MaxWorkersCapsDistinctHolders) {
    const std::string capped = Submit({}, 2);
    ASSERT_EQ(Lease("a")->job_id, capped);
    ASSERT_EQ(Lease("b")->job_id, capped);
    EXPECT_FALSE(Lease("c").has_value()) << "a third worker is beyond the cap";
    // A worker already holding a lease of the job takes more of its tasks.
    EXPECT_EQ(Lease("a")->job_id, capped);
    // Another job is not capped by it.
    const std::string other = Submit({});
    EXPECT_EQ(Lease("c")->job_id, other);
}

TEST_F(WorkerPoolsTest, CapFreesAsLeasesEnd) {
    const std::string capped = Submit({}, 1);
    const TaskAssignment a = *Lease("a");
    EXPECT_FALSE(Lease("b").has_value());
    ASSERT_TRUE(scheduler_.Complete(a.lease_id, "a", testing::UniformResult(a, Rgb(0.5f))).ok());
    const std::optional<TaskAssignment> b = Lease("b");
    ASSERT_TRUE(b.has_value());
    EXPECT_EQ(b->job_id, capped);
}

TEST_F(WorkerPoolsTest, JobNoLiveWorkerCanTakeSaysWhy) {
    const std::string id = Submit({"gpu"});
    EXPECT_EQ(scheduler_.Get(id)->waiting_reason, "waiting for a worker with tags gpu");
    EXPECT_FALSE(Lease("plain").has_value());
    EXPECT_EQ(scheduler_.List()->at(0).waiting_reason, "waiting for a worker with tags gpu");
    ASSERT_TRUE(Lease("gpu-box", {"gpu"}).has_value());
    EXPECT_EQ(scheduler_.Get(id)->waiting_reason, "");
    // The tagged worker falls silent: the job waits for one again.
    now_ += absl::Minutes(5);
    EXPECT_EQ(scheduler_.Get(id)->waiting_reason, "waiting for a worker with tags gpu");
    EXPECT_EQ(scheduler_.Get(Submit({}))->waiting_reason, "") << "an untagged job waits for none";
}

TEST_F(WorkerPoolsTest, WorkersListTheirTags) {
    Lease("w", {"gpu", "linux"});
    const std::vector<WorkerStatus> workers = scheduler_.Workers();
    ASSERT_EQ(workers.size(), 1u);
    EXPECT_EQ(workers[0].tags, (std::vector<std::string>{"gpu", "linux"}));
}

TEST(WorkerPoolsStore, TagsAndMaxWorkersRoundTripTheStoredRecord) {
    JobRecord job;
    job.id = "job-1";
    job.submitted = absl::FromUnixSeconds(1);
    job.spec.tags = {"gpu", "big"};
    job.spec.max_workers = 3;
    lightfarm::v1::StoredJob stored;
    ToProto(job, &stored);
    const absl::StatusOr<JobRecord> back = FromProto(stored);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->spec.tags, job.spec.tags);
    EXPECT_EQ(back->spec.max_workers, 3);
}

TEST(WorkerTags, BadTagsAreRefusedByName) {
    EXPECT_TRUE(ParseTags("", "--tags").ok());
    EXPECT_EQ(*ParseTags("gpu,big-mem_2", "--tags"),
              (std::vector<std::string>{"gpu", "big-mem_2"}));
    const absl::Status upper = ParseTags("GPU", "--tags").status();
    EXPECT_TRUE(absl::IsInvalidArgument(upper));
    EXPECT_NE(upper.message().find("--tags: tag \"GPU\""), std::string::npos) << upper;
    EXPECT_FALSE(ParseTags("a,,b", "--tags").ok());
    EXPECT_FALSE(ParseTags("a,a", "--tags").ok());
    EXPECT_FALSE(ParseTags(std::string(33, 'a'), "--tags").ok());
    std::vector<std::string> many;
    for (int i = 0; i < 33; ++i) many.push_back(absl::StrCat("t", i));
    EXPECT_FALSE(CheckTags(many, "tags").ok());
    JobSpec spec;
    spec.tags = {"no spaces"};
    EXPECT_NE(CheckJobSettings(spec).message().find("tags: tag \"no spaces\""), std::string::npos);
    spec.tags = {};
    spec.max_workers = -1;
    EXPECT_NE(CheckJobSettings(spec).message().find("max_workers -1"), std::string::npos);
}

}  // namespace
}  // namespace lf
