// A worker stops a radiosity task within a second of a cancel (or SIGTERM) in every phase:
// meshing, form factors and the solve each return Cancelled soon after the flag is set from
// another thread. Each call here would run for many seconds, or without end, if it ignored it.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <thread>

#include "lf/core/patch_mesh.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/radiosity.h"
#include "test_scenes.h"

namespace lf {
namespace {

using Clock = std::chrono::steady_clock;

// Runs `call`, sets `cancel` from another thread once it has been running a little while (the
// delay only puts the cancel in the middle of the phase), and returns the call's status and the
// seconds from the cancel to the call's return.
template <typename Call>
std::pair<absl::Status, double> CancelDuring(std::atomic<bool>& cancel, Call call) {
    std::atomic<int64_t> cancelled_at{0};
    std::thread canceller([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        cancelled_at = Clock::now().time_since_epoch().count();
        cancel = true;
    });
    const absl::Status status = call();
    const Clock::time_point returned = Clock::now();
    canceller.join();
    const Clock::time_point set{Clock::duration(cancelled_at.load())};
    return {status, std::chrono::duration<double>(returned - set).count()};
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

TEST_F(RadiosityCancelTest, MeshingReturnsCancelledWithinASecond) {
    std::atomic<bool> cancel{false};
    PatchMeshOptions options;
    options.patches = int64_t(1) << 24;  // the most a job may ask: seconds of meshing
    options.cancel = &cancel;
    const auto [status, seconds] =
        CancelDuring(cancel, [&] { return PatchMesh::Build(*scene_, options).status(); });
    EXPECT_TRUE(absl::IsCancelled(status)) << status;
    EXPECT_LT(seconds, 1.0);
    std::printf("meshing: returned %.3f s after the cancel\n", seconds);
}

TEST_F(RadiosityCancelTest, FormFactorsReturnCancelledWithinASecond) {
    std::atomic<bool> cancel{false};
    RadiosityOptions options;
    options.patches = 12000;  // form factors: half a minute of one core
    options.threads = 1;
    options.cancel = &cancel;
    const auto [status, seconds] =
        CancelDuring(cancel, [&] { return PrepareRadiosity(*embree_, options).status(); });
    EXPECT_TRUE(absl::IsCancelled(status)) << status;
    EXPECT_NE(status.message().find("form factors"), std::string_view::npos) << status;
    EXPECT_LT(seconds, 1.0);
    std::printf("form factors: returned %.3f s after the cancel\n", seconds);
}

TEST_F(RadiosityCancelTest, SolveReturnsCancelledWithinASecondForEverySolver) {
    // A closed furnace whose walls reflect nearly all light: each sweep shrinks the error by
    // about 1 - 1e-6, so no solve reaches a fixed point for many minutes.
    const Scene furnace = testing::MakeFurnace(1.0, Vec3d(0, 0, 0), 0.999999f, 1.0f, 4);
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(furnace);
    ASSERT_TRUE(embree.ok()) << embree.status();
    absl::StatusOr<PatchMesh> mesh = PatchMesh::Build(furnace, {0, 200});
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    const FormFactors form_factors = ComputeFormFactors(**embree, *mesh);
    const RadiositySystem system = MakeRadiositySystem(**embree, *mesh, form_factors);
    for (RadiositySolver solver :
         {RadiositySolver::kJacobi, RadiositySolver::kGaussSeidel, RadiositySolver::kShooting}) {
        std::atomic<bool> cancel{false};
        // A tolerance no solve reaches and no iteration limit: it ends only when cancelled.
        const SolveOptions options{solver, 1e-300, INT_MAX, &cancel};
        const auto [status, seconds] =
            CancelDuring(cancel, [&] { return SolveRadiosity(system, options).status(); });
        EXPECT_TRUE(absl::IsCancelled(status)) << RadiositySolverName(solver) << ": " << status;
        EXPECT_LT(seconds, 1.0) << RadiositySolverName(solver);
        std::printf("%s solve: returned %.3f s after the cancel\n", RadiositySolverName(solver),
                    seconds);
    }
}

TEST_F(RadiosityCancelTest, SweepChunkFormFactorsReturnCancelledWithinASecond) {
    std::atomic<bool> cancel{false};
    RadiosityOptions options;
    options.patches = 12000;
    const auto [status, seconds] = CancelDuring(cancel, [&] {
        return RadiositySweepChunk::Build(*embree_, options, 0, 1, &cancel).status();
    });
    EXPECT_TRUE(absl::IsCancelled(status)) << status;
    EXPECT_LT(seconds, 1.0);
}

}  // namespace
}  // namespace lf
