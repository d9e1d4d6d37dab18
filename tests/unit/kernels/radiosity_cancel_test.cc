// A worker stops a radiosity task soon after a cancel (or SIGTERM) in every phase: meshing, form
// factors and the solve each return Cancelled once the flag is set from another thread. "Soon" is
// counted in units of work (polls of the flag, pairs of patches), not seconds: the flag is set
// at a given poll, so it falls mid-phase however loaded the machine is. Each call here would run
// for many seconds, or without end, if it ignored it.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <thread>

#include "lf/core/cancel.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/radiosity.h"
#include "test_scenes.h"

namespace lf {
namespace {

// Counts the polls of cancel flags while it lives and sets `cancel` at poll number `at`.
class CancelAtPoll {
  public:
    CancelAtPoll(std::atomic<bool>& cancel, int64_t at) : at_(at) {
        SetCancelPollObserverForTesting([this, &cancel] {
            if (++polls_ == at_) cancel = true;
        });
    }
    ~CancelAtPoll() { SetCancelPollObserverForTesting(nullptr); }

    bool reached() const { return polls_ >= at_; }
    int64_t polls_after() const { return polls_ - at_; }  // those after the one that set it

  private:
    const int64_t at_;
    std::atomic<int64_t> polls_{0};
};

// Runs `call` on one thread of a TBB arena of its own (so polls come in a fixed order) and
// returns its result. A call that ignored the cancel would run for minutes or without end: past
// a deadline far above the milliseconds a cancelled call takes, the test fails instead of hanging.
template <typename Call>
auto OnOneThread(Call call) -> decltype(call()) {
    std::packaged_task<decltype(call())()> task([&] {
        tbb::task_arena arena(1);
        return arena.execute(call);
    });
    auto result = task.get_future();
    std::thread thread(std::move(task));
    if (result.wait_for(std::chrono::seconds(120)) == std::future_status::timeout) {
        std::fprintf(stderr, "still running two minutes after the cancel: it was ignored\n");
        std::abort();
    }
    thread.join();
    return result.get();
}

class RadiosityCancelTest : public ::testing::Test {
  protected:
    void SetUp() override {
        absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
        ASSERT_TRUE(scene.ok()) << scene.status();
        scene_ = std::make_unique<Scene>(std::move(*scene));
        absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene_);
        ASSERT_TRUE(embree.ok()) << embree.status();
        embree_ = std::move(*embree);
    }
    std::unique_ptr<Scene> scene_;
    std::unique_ptr<EmbreeScene> embree_;
};

// Meshing polls once per row of a triangle's grid (a thousand rows are a few triangles' worth
// of the 34k rows here) and returns at the poll that sees the flag.
TEST_F(RadiosityCancelTest, MeshingReturnsCancelledAtThePollThatSeesTheCancel) {
    std::atomic<bool> cancel{false};
    PatchMeshOptions options;
    options.patches = int64_t(1) << 24;  // the most a job may ask: seconds of meshing
    options.cancel = &cancel;
    const CancelAtPoll cancel_at(cancel, 1000);
    const absl::Status status =
        OnOneThread([&] { return PatchMesh::Build(*scene_, options).status(); });
    EXPECT_TRUE(absl::IsCancelled(status)) << status;
    EXPECT_TRUE(cancel_at.reached());
    EXPECT_EQ(cancel_at.polls_after(), 0);
}

// Form factors poll before each row of a block of two patch groups: each poll before the cancel
// lets at most one row of pairs through (a group's size), none after it.
TEST_F(RadiosityCancelTest, FormFactorsStopWithinARowOfTheCancel) {
    absl::StatusOr<PatchMesh> mesh = PatchMesh::Build(*scene_, {0, 12000});
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    std::atomic<bool> cancel{false};
    FormFactorOptions options;
    options.cancel = &cancel;
    constexpr int64_t kCancelAt = 5000;
    const CancelAtPoll cancel_at(cancel, kCancelAt);
    // All the pairs: half a minute of one core.
    const FormFactors form_factors =
        OnOneThread([&] { return ComputeFormFactors(*embree_, *mesh, options); });
    EXPECT_TRUE(cancel_at.reached());
    EXPECT_GT(form_factors.work().pairs, 0);
    EXPECT_LE(form_factors.work().pairs, kCancelAt * options.group_size);
    std::printf("form factors: %lld pairs evaluated, %lld polls after the cancel\n",
                static_cast<long long>(form_factors.work().pairs),
                static_cast<long long>(cancel_at.polls_after()));
}

// PrepareRadiosity meshes (under a thousand polls for 12k patches), then computes the form
// factors (over a million polls): the cancel at poll 20k ends it there, with the phase named.
TEST_F(RadiosityCancelTest, PrepareReturnsCancelledDuringTheFormFactors) {
    std::atomic<bool> cancel{false};
    RadiosityOptions options;
    options.patches = 12000;  // form factors: half a minute of one core
    options.threads = 1;
    options.cancel = &cancel;
    const CancelAtPoll cancel_at(cancel, 20000);
    const absl::Status status =
        OnOneThread([&] { return PrepareRadiosity(*embree_, options).status(); });
    EXPECT_TRUE(absl::IsCancelled(status)) << status;
    EXPECT_NE(status.message().find("form factors"), std::string_view::npos) << status;
    EXPECT_TRUE(cancel_at.reached());
}

// The solvers poll before each patch group's gather (Jacobi: also once after each sweep; shooting:
// before each shot). Gauss-Seidel and shooting return at the poll that sees the flag; Jacobi's
// sweep skips its remaining groups, one poll each, and returns before the next sweep.
TEST_F(RadiosityCancelTest, SolveReturnsCancelledMidSweepForEverySolver) {
    // A closed furnace whose walls reflect nearly all light: each sweep shrinks the error by
    // about 1 - 1e-6, so no solve reaches a fixed point for many minutes.
    const Scene furnace = testing::MakeFurnace(1.0, Vec3d(0, 0, 0), 0.999999f, 1.0f, 4);
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(furnace);
    ASSERT_TRUE(embree.ok()) << embree.status();
    absl::StatusOr<PatchMesh> mesh = PatchMesh::Build(furnace, {0, 200});
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    const FormFactors form_factors = ComputeFormFactors(**embree, *mesh);
    const RadiositySystem system = MakeRadiositySystem(**embree, *mesh, form_factors);
    const int64_t groups = int64_t(form_factors.groups().size());
    for (RadiositySolver solver :
         {RadiositySolver::kJacobi, RadiositySolver::kGaussSeidel, RadiositySolver::kShooting}) {
        std::atomic<bool> cancel{false};
        // A tolerance no solve reaches and no iteration limit: it ends only when cancelled.
        const SolveOptions options{solver, 1e-300, INT_MAX, &cancel};
        // Ten sweeps (or shots) and half of the eleventh in.
        const CancelAtPoll cancel_at(cancel, 10 * (groups + 1) + groups / 2);
        const absl::Status status =
            OnOneThread([&] { return SolveRadiosity(system, options).status(); });
        EXPECT_TRUE(absl::IsCancelled(status)) << RadiositySolverName(solver) << ": " << status;
        EXPECT_TRUE(cancel_at.reached()) << RadiositySolverName(solver);
        EXPECT_LE(cancel_at.polls_after(), solver == RadiositySolver::kJacobi ? groups : 0)
            << RadiositySolverName(solver);
    }
}

TEST_F(RadiosityCancelTest, SweepChunkReturnsCancelledDuringTheFormFactors) {
    std::atomic<bool> cancel{false};
    RadiosityOptions options;
    options.patches = 12000;
    const CancelAtPoll cancel_at(cancel, 20000);
    const absl::Status status = OnOneThread([&] {
        auto chunks = RadiositySweepChunks::Make(*embree_, options, 1, &cancel);
        return chunks.ok() ? (*chunks)->Link(*embree_, 0, &cancel) : chunks.status();
    });
    EXPECT_TRUE(absl::IsCancelled(status)) << status;
    EXPECT_NE(status.message().find("form factors"), std::string_view::npos) << status;
    EXPECT_TRUE(cancel_at.reached());
}

}  // namespace
}  // namespace lf
