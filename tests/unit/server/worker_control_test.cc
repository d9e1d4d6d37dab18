// Worker control (issue 30): a disabled worker takes no new task while its current one goes on;
// a drained one finishes its task, shows "draining" then "drained", and takes none; the control
// is kept by name and survives a coordinator restart; a silent worker is listed as offline until
// forget_workers_after, then forgotten.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <set>

#include "lease_results.h"
#include "lf/server/farm.h"
#include "lf/server/scheduler.h"
#include "lf/server/worker_state_store.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

class WorkerControlTest : public ::testing::Test {
  protected:
    WorkerControlTest() : scheduler_(Options(), store_, [this] { return now_; }) {}

    static SchedulerOptions Options() {
        SchedulerOptions o;
        o.lease = absl::Seconds(10);
        o.forget_workers_after = absl::Minutes(30);
        return o;
    }

    std::string Submit() {
        JobSpec spec;
        spec.name = "control";
        spec.plan = {16, 16, 4, 8, 2};  // 8 tasks
        absl::StatusOr<std::string> id = scheduler_.Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return *id;
    }

    std::optional<TaskAssignment> Lease(const std::string& id, const std::string& name) {
        const WorkerDescription about{.name = name};
        return scheduler_.LeaseTask(id, absl::InfinitePast(), &about);
    }

    // The state `lightfarm workers` shows for worker `id`; "" when it is not listed.
    std::string StateOf(const std::string& id) {
        for (const WorkerStatus& w : scheduler_.Workers()) {
            if (w.id == id) return WorkerStateName(lf::StateOf(w));
        }
        return "";
    }

    absl::Time now_ = absl::FromUnixSeconds(1'000'000);
    InMemoryJobStore store_;
    Scheduler scheduler_;
};

TEST_F(WorkerControlTest, DisabledWorkerTakesNothingNewItsTaskGoesOn) {
    Submit();
    const TaskAssignment held = *Lease("box-1", "box");
    ASSERT_EQ(scheduler_.WorkerKey("box-1"), "box") << "an id names its worker's name";
    scheduler_.SetWorkerControl("box", WorkerControl::kDisabled);
    EXPECT_EQ(StateOf("box-1"), "disabled");
    EXPECT_FALSE(Lease("box-1", "box").has_value());
    EXPECT_TRUE(scheduler_.Heartbeat(held.lease_id, "box-1")) << "its current task goes on";
    ASSERT_TRUE(
        scheduler_.Complete(held.lease_id, "box-1", testing::UniformResult(held, Rgb(0.5f))).ok());
    EXPECT_FALSE(Lease("box-1", "box").has_value());
    EXPECT_TRUE(Lease("other-1", "other").has_value()) << "other workers are not affected";
    scheduler_.SetWorkerControl("box", WorkerControl::kEnabled);
    EXPECT_EQ(StateOf("box-1"), "idle");
    EXPECT_TRUE(Lease("box-1", "box").has_value());
}

TEST_F(WorkerControlTest, DrainedWorkerFinishesItsTaskThenTakesNone) {
    Submit();
    const TaskAssignment held = *Lease("box-1", "box");
    scheduler_.SetWorkerControl("box", WorkerControl::kDrain);
    EXPECT_EQ(StateOf("box-1"), "draining");
    ASSERT_TRUE(
        scheduler_.Complete(held.lease_id, "box-1", testing::UniformResult(held, Rgb(0.5f))).ok());
    EXPECT_EQ(scheduler_.Tasks(held.job_id)->at(size_t(held.task.index)).state,
              TaskStatus::State::kDone)
        << "its result merged";
    EXPECT_EQ(StateOf("box-1"), "drained");
    EXPECT_FALSE(Lease("box-1", "box").has_value());
}

TEST_F(WorkerControlTest, ControlIsKeptByNameForEveryWorkerOfIt) {
    Submit();
    Lease("box-1", "box");
    scheduler_.SetWorkerControl(*scheduler_.WorkerKey("box"), WorkerControl::kDisabled);
    // Another process of the same name (a restarted worker) is disabled too.
    EXPECT_FALSE(Lease("box-2", "box").has_value());
    EXPECT_EQ(StateOf("box-2"), "disabled");
    EXPECT_FALSE(scheduler_.WorkerKey("nobody").has_value());
}

TEST_F(WorkerControlTest, SilentWorkerIsListedOfflineThenForgotten) {
    Lease("box-1", "box");
    now_ += absl::Seconds(11);
    EXPECT_EQ(StateOf("box-1"), "offline");
    const std::vector<WorkerStatus> listed = scheduler_.Workers();
    ASSERT_EQ(listed.size(), 1u);
    EXPECT_EQ(listed[0].name, "box");
    EXPECT_EQ(listed[0].last_seen, now_ - absl::Seconds(11));
    EXPECT_EQ(scheduler_.Load().workers_live, 0) << "offline is not live";
    EXPECT_EQ(scheduler_.WorkerKey("box-1"), "box") << "an offline worker can be disabled";
    // It comes back: live again, as it was.
    Lease("box-1", "box");
    EXPECT_EQ(StateOf("box-1"), "idle");
    now_ += absl::Minutes(31);
    EXPECT_EQ(StateOf("box-1"), "");
}

TEST(WorkerRegistryOffline, MadeUpIdsKeepAtMostTheCapOldestDroppedFirst) {
    const absl::Time t0 = absl::FromUnixSeconds(1'000'000);
    WorkerRegistry r(absl::Seconds(10), absl::Hours(1));
    const int n = int(WorkerRegistry::kMaxOffline) + 100;
    for (int i = 0; i < n; ++i) r.Seen("made-up-" + std::to_string(i), t0 + absl::Microseconds(i));
    EXPECT_EQ(r.ForgetSilent(t0 + absl::Seconds(11)), n);
    EXPECT_EQ(r.size(), 0u);
    std::set<std::string> offline;
    for (const WorkerRegistry::Entry& e : r.Offline()) offline.insert(e.id);
    EXPECT_EQ(offline.size(), WorkerRegistry::kMaxOffline);
    EXPECT_FALSE(offline.count("made-up-99"));
    EXPECT_TRUE(offline.count("made-up-100"));
}

TEST(WorkerStateStore, ControlsSurviveAReopenAndEnableRemovesThem) {
    const fs::path dir =
        fs::temp_directory_path() / ("lf_worker_states_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string path = (dir / "workers.db").string();
    {
        auto store = WorkerStateStore::Open(path);
        ASSERT_TRUE(store.ok()) << store.status();
        ASSERT_TRUE((*store)->Put("a", WorkerControl::kDisabled).ok());
        ASSERT_TRUE((*store)->Put("b", WorkerControl::kDrain).ok());
        ASSERT_TRUE((*store)->Put("c", WorkerControl::kDisabled).ok());
        ASSERT_TRUE((*store)->Put("c", WorkerControl::kEnabled).ok());
    }
    auto store = WorkerStateStore::Open(path);
    ASSERT_TRUE(store.ok()) << store.status();
    const auto controls = (*store)->List();
    ASSERT_TRUE(controls.ok()) << controls.status();
    EXPECT_EQ(*controls, (std::map<std::string, WorkerControl>{{"a", WorkerControl::kDisabled},
                                                               {"b", WorkerControl::kDrain}}));
    fs::remove_all(dir);
}

TEST(FarmWorkerControl, DisabledWorkerStaysDisabledAfterARestart) {
    const fs::path dir =
        fs::temp_directory_path() / ("lf_worker_control_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    FarmOptions options;
    options.data_dir = dir.string();
    {
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        const WorkerDescription about{.name = "box"};
        (*farm)->scheduler().LeaseTask("box-1", absl::InfinitePast(), &about);
        EXPECT_TRUE(
            absl::IsNotFound((*farm)->SetWorkerState("nobody", WorkerControl::kDisabled).status()));
        absl::StatusOr<std::vector<WorkerStatus>> set =
            (*farm)->SetWorkerState("box-1", WorkerControl::kDisabled);
        ASSERT_TRUE(set.ok()) << set.status();
        ASSERT_EQ(set->size(), 1u);
        EXPECT_EQ(set->at(0).control, WorkerControl::kDisabled);
    }
    absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
    ASSERT_TRUE(farm.ok()) << farm.status();
    const WorkerDescription about{.name = "box"};
    (*farm)->scheduler().LeaseTask("box-9", absl::InfinitePast(), &about);
    const std::vector<WorkerStatus> workers = (*farm)->scheduler().Workers();
    ASSERT_EQ(workers.size(), 1u);
    EXPECT_EQ(workers[0].control, WorkerControl::kDisabled);
    EXPECT_TRUE((*farm)->SetWorkerState("box", WorkerControl::kEnabled).ok());
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
