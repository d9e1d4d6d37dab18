// The coordinator's glue for the splatting methods (lf/job/splat_plan.h): a light job is planned
// into light-path ranges, its results (camera part + splats) merge exactly once into the bits a
// SplatMerger makes of the same results, a restarted scheduler merges the recorded results
// (splats included) to the same bits, and results that do not fit their task, or do not decode,
// are refused naming the job, the task and the worker, the task going back to the queue.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "lf/core/splat_codec.h"
#include "lf/core/tile_codec.h"
#include "lf/job/splat_merge.h"
#include "lf/job/splat_result_codec.h"
#include "lf/job/splat_settings.h"
#include "lf/server/farm.h"
#include "lf/server/scheduler.h"
#include "lf/server/sqlite_job_store.h"
#include "test_dir.h"
#include "test_job_store.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 16, kHeight = 8;

// A light job: 16x8, 4 light paths per pixel-equivalent (512) in --passes 4 ranges of 128.
JobSpec LightSpec() {
    JobSpec spec;
    spec.name = "light";
    spec.method = "light";
    spec.plan = {kWidth, kHeight, 4, 8, 4};
    return spec;
}

// A task's made-up result, a pure function of its light paths as a kernel's is: path i splats
// onto a pixel and a value of i, in half i & 1; the stats count its paths.
struct Result {
    TileSums camera{PixelRect{}};
    SplatList splats{kWidth, kHeight};
};
Result Fake(const TaskAssignment& lease) {
    Result r;
    r.camera = TileSums(lease.task.rect);
    for (uint64_t i = lease.path_begin; i < lease.path_end; ++i) {
        const int pixel = int((i * 2654435761u) % (kWidth * kHeight));
        r.splats.Add(pixel % kWidth, pixel / kWidth, int(i & 1),
                     Rgb(0.01f * float(i % 13), 0.5f, float(i % 5)));
    }
    r.camera.stats.rays = lease.path_end - lease.path_begin;
    return r;
}

bool SameBits(const Image& a, const Image& b) {
    if (a.channels().size() != b.channels().size()) return false;
    for (const auto& [name, x] : a.channels()) {
        const std::vector<float>* y = b.FindChannel(name);
        if (!y || y->size() != x.size() ||
            std::memcmp(x.data(), y->data(), x.size() * sizeof(float)) != 0) {
            return false;
        }
    }
    return true;
}

class SplatSchedulerTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_splat_sched");
        fs::create_directories(dir_ / "tiles");
    }
    void TearDown() override { fs::remove_all(dir_); }

    SchedulerOptions InFiles() const {
        SchedulerOptions options;
        options.tile_stores = [dir = (dir_ / "tiles").string()](std::vector<PixelRect> tiles,
                                                                uint32_t aovs) {
            return MakeFileTileStore(dir, std::move(tiles), aovs);
        };
        return options;
    }

    // The image a SplatMerger makes of every task's fake result: what the job must give.
    static Image Expected() {
        absl::StatusOr<SplatPlanSettings> plan = SplatPlanSettingsOf("light", LightSpec().plan);
        absl::StatusOr<std::vector<SplatTask>> tasks = PlanSplatRender(*plan);
        absl::StatusOr<std::unique_ptr<SplatMerger>> merger =
            SplatMerger::Make(kWidth, kHeight, plan->tile, plan->kind, *tasks);
        for (const SplatTask& t : *tasks) {
            TaskAssignment lease;
            lease.task = {t.index, t.rect, t.sample_begin, t.sample_end};
            lease.path_begin = t.path_begin;
            lease.path_end = t.path_end;
            Result r = Fake(lease);
            EXPECT_TRUE((*merger)->Add(t.index, r.camera, r.splats).ok());
        }
        return *(*merger)->Snapshot();
    }

    fs::path dir_;
};

TEST_F(SplatSchedulerTest, LightJobIsPlannedInPathRangesAndMergesEachResultOnce) {
    InMemoryJobStore store;
    Scheduler scheduler(InFiles(), store);
    const std::string id = *scheduler.Submit(LightSpec());
    EXPECT_EQ(scheduler.Get(id)->tasks_total, 4);
    std::vector<TaskAssignment> leases;
    for (int i = 0; i < 4; ++i) leases.push_back(*scheduler.LeaseTask("w"));
    uint64_t next = 0;
    for (const TaskAssignment& lease : leases) {
        EXPECT_EQ(lease.task.rect.Area(), 0) << "light tasks have no camera part";
        EXPECT_EQ(lease.path_begin, next);
        next = lease.path_end;
    }
    EXPECT_EQ(next, uint64_t(4 * kWidth * kHeight));
    // In reverse order, the second result twice: the same bits.
    for (int i = 3; i >= 0; --i) {
        Result r = Fake(leases[size_t(i)]);
        ASSERT_TRUE(scheduler.Complete(leases[size_t(i)].lease_id, "w", r.camera, &r.splats).ok());
        if (i == 1) {
            Result again = Fake(leases[1]);
            EXPECT_TRUE(
                scheduler.Complete(leases[1].lease_id, "w", again.camera, &again.splats).ok());
        }
    }
    const JobRecord record = *scheduler.Get(id);
    EXPECT_EQ(record.tasks_done, 4);
    EXPECT_EQ(record.stats.rays, next) << "the stats of every task, once";
    EXPECT_TRUE(SameBits(scheduler.Snapshot(id)->image, Expected()));
}

TEST_F(SplatSchedulerTest, RestartMergesTheRecordedSplatsToTheSameBits) {
    std::string id;
    {
        std::unique_ptr<SqliteJobStore> store = lf::testing::OpenJobStore(dir_);
        Scheduler scheduler(InFiles(), *store);
        id = *scheduler.Submit(LightSpec());
        for (int i = 0; i < 2; ++i) {
            const TaskAssignment lease = *scheduler.LeaseTask("w");
            Result r = Fake(lease);
            ASSERT_TRUE(scheduler.Complete(lease.lease_id, "w", r.camera, &r.splats).ok());
        }
        (void)scheduler.LeaseTask("w");  // leased, never completed: lost with the server
    }
    fs::remove_all(dir_ / "tiles");  // the coordinator sweeps scratch/ on start
    fs::create_directories(dir_ / "tiles");
    std::unique_ptr<SqliteJobStore> store = lf::testing::OpenJobStore(dir_);
    Scheduler scheduler(InFiles(), *store);
    ASSERT_TRUE(scheduler.Recover().ok());
    EXPECT_EQ(scheduler.Get(id)->tasks_done, 2);
    bool rendered = false;
    while (std::optional<TaskAssignment> lease = scheduler.LeaseTask("w")) {
        Result r = Fake(*lease);
        absl::StatusOr<Scheduler::Completion> done =
            scheduler.Complete(lease->lease_id, "w", r.camera, &r.splats);
        ASSERT_TRUE(done.ok()) << done.status();
        rendered = done->job_rendered;
    }
    EXPECT_TRUE(rendered);
    EXPECT_EQ(scheduler.Get(id)->tasks_done, 4);
    EXPECT_TRUE(SameBits(scheduler.Snapshot(id)->image, Expected()));
}

TEST_F(SplatSchedulerTest, ResultsThatDoNotFitTheirTaskAreRefusedNamingJobTaskAndWorker) {
    InMemoryJobStore store;
    Scheduler scheduler(InFiles(), store);
    // Three tasks, one refusal each (three on one task would fail the job); w1 is not
    // blocklisted by its three (issue 30's blocklist would fail the job of its only worker).
    JobSpec spec = LightSpec();
    spec.blocklist_after = 4;
    const std::string id = *scheduler.Submit(spec);
    std::vector<TaskAssignment> leases;
    for (int i = 0; i < 3; ++i) leases.push_back(*scheduler.LeaseTask("w1"));
    auto expect_refused = [&](const TileSums& camera, SplatList* splats, const std::string& why) {
        const TaskAssignment lease = leases.back();
        leases.pop_back();
        absl::StatusOr<Scheduler::Completion> done =
            scheduler.Complete(lease.lease_id, "w1", camera, splats);
        ASSERT_EQ(done.status().code(), absl::StatusCode::kInvalidArgument) << why;
        const std::string message(done.status().message());
        EXPECT_NE(message.find("job=" + id), std::string::npos) << message;
        EXPECT_NE(message.find("task=" + std::to_string(lease.task.index)), std::string::npos)
            << message;
        EXPECT_NE(message.find("w1"), std::string::npos) << message;
        EXPECT_NE(message.find(why), std::string::npos) << message;
    };
    SplatList other_frame(kWidth + 1, kHeight);
    expect_refused(TileSums(PixelRect{}), &other_frame, "");
    expect_refused(TileSums(PixelRect{}), nullptr, "without its splats");
    SplatList splats(kWidth, kHeight);
    expect_refused(TileSums(PixelRect{0, 0, 8, 8}), &splats, "");
    // Each refusal put its task back as a counted failure; nothing merged.
    const JobRecord record = *scheduler.Get(id);
    EXPECT_EQ(record.tasks_done, 0);
    EXPECT_EQ(record.retries, 3);
    EXPECT_EQ(record.state, JobState::kRunning);
}

TEST_F(SplatSchedulerTest, SplatsInATileJobsResultAreRefused) {
    InMemoryJobStore store;
    Scheduler scheduler(InFiles(), store);
    JobSpec spec = LightSpec();
    spec.method = "path";
    ASSERT_TRUE(scheduler.Submit(spec).ok());
    const TaskAssignment lease = *scheduler.LeaseTask("w");
    TileSums sums(lease.task.rect);
    SplatList splats(kWidth, kHeight);
    absl::StatusOr<Scheduler::Completion> done =
        scheduler.Complete(lease.lease_id, "w", sums, &splats);
    EXPECT_EQ(done.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(done.status().message().find("splats in the result of a tile task"),
              std::string::npos)
        << done.status();
}

// Through the farm's decoding: hostile splat bytes fail the task, naming job, task and worker.
TEST_F(SplatSchedulerTest, UndecodableSplatsFailTheTaskNamingJobTaskAndWorker) {
    FarmOptions options;
    options.data_dir = (dir_ / "farm").string();
    absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
    ASSERT_TRUE(farm.ok()) << farm.status();
    JobSpec spec = LightSpec();
    const std::string id = *(*farm)->scheduler().Submit(spec);
    const TaskAssignment lease = *(*farm)->scheduler().LeaseTask("w9");
    Result r = Fake(lease);
    std::string splats = EncodeSplatList(r.splats);
    const std::string camera = EncodeTileSums(r.camera);
    std::vector<std::string> hostile = {
        "LFSP",                                                             // a header cut short
        splats.substr(0, splats.size() - 1),                                // an entry cut short
        std::string("XXXX") + splats.substr(4),                             // not LFSP
        splats.substr(0, 12) + std::string(8, '\xff') + splats.substr(20),  // a huge count
    };
    for (const std::string& bytes : hostile) {
        const absl::Status s =
            (*farm)->Complete(lease.lease_id, "w9", camera, std::nullopt, std::string_view(bytes));
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
        const std::string message(s.message());
        EXPECT_NE(message.find("job=" + id + " task=" + std::to_string(lease.task.index)),
                  std::string::npos)
            << message;
        EXPECT_NE(message.find("w9"), std::string::npos) << message;
    }
    // The first refusal gave the task back (the later ones find no current lease): it is
    // queued again, and the job runs on.
    EXPECT_EQ((*farm)->scheduler().Get(id)->retries, 1);
    EXPECT_EQ((*farm)->scheduler().Get(id)->tasks_done, 0);
    (*farm)->scheduler().Shutdown();
}

TEST(SplatResultCodec, RoundTripsAndRefusesWhatIsNotOne) {
    TileSums camera(PixelRect{2, 3, 4, 2});
    camera.pixels[5].Add(1, Rgb(0.25f, 1, 2));
    camera.stats.rays = 77;
    SplatList splats(kWidth, kHeight);
    splats.Add(3, 4, 1, Rgb(1, 2, 3));
    const std::string bytes = EncodeSplatResult(camera, splats);
    absl::StatusOr<SplatResult> back = DecodeSplatResult(bytes);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(EncodeTileSums(back->camera), EncodeTileSums(camera));
    EXPECT_EQ(back->splats.entries(), splats.entries());
    // No camera part: a 0x0 tile with the stats only.
    TileSums none{PixelRect{}};
    none.stats.rays = 5;
    absl::StatusOr<SplatResult> stats_only = DecodeSplatResult(EncodeSplatResult(none, splats));
    ASSERT_TRUE(stats_only.ok()) << stats_only.status();
    EXPECT_EQ(stats_only->camera.rect.Area(), 0);
    EXPECT_EQ(stats_only->camera.stats.rays, 5u);
    for (const std::string& bad :
         {std::string(), bytes.substr(0, 10), std::string("LFFX") + bytes.substr(4),
          bytes.substr(0, 8) + std::string(8, '\x7f') + bytes.substr(16),
          bytes.substr(0, bytes.size() - 3)}) {
        EXPECT_EQ(DecodeSplatResult(bad).status().code(), absl::StatusCode::kInvalidArgument);
    }
}

}  // namespace
}  // namespace lf
