// What a farm worker shares between the chunks it holds (lf::RadiositySweepChunks): one mesh and
// system (or cluster tree) for all of them, one pull of each sweep's radiosity, and the mesh and
// tree again for the display. Each must give the bits of a worker holding one chunk alone.
#include <gtest/gtest.h>

#include <algorithm>

#include "lf/core/scene_loader.h"
#include "lf/job/radiosity_solve.h"
#include "lf/kernels/radiosity.h"

namespace lf {
namespace {

bool SameBits(std::span<const Rgb> a, std::span<const Rgb> b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                      [](Rgb x, Rgb y) { return x.r == y.r && x.g == y.g && x.b == y.b; });
}

class RadiositySweepChunksTest : public ::testing::TestWithParam<bool> {
  protected:
    void SetUp() override {
        auto loaded = LoadScene(std::string(LF_TEST_SCENES) + "/cornell_box.json");
        ASSERT_TRUE(loaded.ok()) << loaded.status();
        scene_ = std::move(*loaded);
        auto embree = EmbreeScene::Build(scene_);
        ASSERT_TRUE(embree.ok()) << embree.status();
        embree_ = std::move(*embree);
        options_.hierarchical = GetParam();
        options_.link_error = 1e-3;
        options_.patches = 600;
        options_.tolerance = 1e-4;
        // Every chunk in one worker's hands, linked out of order; and each chunk alone.
        auto all = RadiositySweepChunks::Make(*embree_, options_, kChunks);
        ASSERT_TRUE(all.ok()) << all.status();
        all_ = std::move(*all);
        for (int c : {2, 0, 1}) ASSERT_TRUE(all_->Link(*embree_, c).ok());
        for (int c = 0; c < kChunks; ++c) {
            auto alone = RadiositySweepChunks::Make(*embree_, options_, kChunks);
            ASSERT_TRUE(alone.ok()) << alone.status();
            ASSERT_TRUE((*alone)->Link(*embree_, c).ok());
            alone_.push_back(std::move(*alone));
        }
    }

    static constexpr int kChunks = 3;
    Scene scene_;  // outlives embree_, which keeps a reference
    std::unique_ptr<EmbreeScene> embree_;
    RadiosityOptions options_;
    std::unique_ptr<RadiositySweepChunks> all_;
    std::vector<std::unique_ptr<RadiositySweepChunks>> alone_;
};

// Every chunk swept from the shared holder with its one pull gives what the chunk held alone
// gives with its own, sweep after sweep; the link figures are the same too, and the shares of
// the solver's bytes add up over the chunks. The solution's display from the holder is
// RadiosityRendererFor's, report included.
TEST_P(RadiositySweepChunksTest, SharedMeshTreeAndPullGiveTheBitsOfAChunkAlone) {
    RadiositySolve solve(kChunks, options_.tolerance, options_.max_iterations);
    std::vector<Rgb> h = all_->start();  // the gathered irradiance
    std::vector<bool> has_sides(kChunks);
    for (;;) {
        const std::vector<NodeExitance> pulled = all_->Pull(h);
        EXPECT_EQ(pulled.empty(), !GetParam()) << "the flat method pulls nothing";
        for (int c = 0; c < kChunks; ++c) {
            auto own = alone_[size_t(c)]->Sweep(c, solve.sweep(), h);
            auto shared = all_->Sweep(c, solve.sweep(), h, pulled);
            ASSERT_TRUE(own.ok()) << own.status();
            ASSERT_TRUE(shared.ok()) << shared.status();
            EXPECT_TRUE(SameBits(own->output, shared->output)) << "chunk " << c;
            EXPECT_EQ(own->change, shared->change);
            has_sides[size_t(c)] = !shared->output.empty();
            ASSERT_TRUE(solve.Add(*shared).ok());
        }
        auto outcome = solve.FinishSweep();
        ASSERT_TRUE(outcome.ok()) << outcome.status();
        h = std::move(outcome->radiosity);
        if (outcome->converged) break;
    }
    // The tree and per-side data split over the chunks: the shares add up to one copy's bytes.
    int64_t shares = 0, alone_shares = 0;
    for (int c = 0; c < kChunks; ++c) {
        const RadiosityReport mine = all_->LinkReport(c), alone = alone_[size_t(c)]->LinkReport(c);
        EXPECT_EQ(mine.cluster_links, alone.cluster_links) << "chunk " << c;
        EXPECT_EQ(mine.side_links, alone.side_links) << "chunk " << c;
        EXPECT_EQ(mine.link_bytes, alone.link_bytes) << "chunk " << c;
        // A chunk of no groups (ChunkGroups' taper may leave the last ones empty) has none.
        EXPECT_EQ(mine.cluster_links + mine.side_links > 0, GetParam() && has_sides[size_t(c)])
            << "chunk " << c;
        shares += int64_t(mine.solver_bytes) - int64_t(mine.link_bytes);
        alone_shares += int64_t(alone.solver_bytes) - int64_t(alone.link_bytes);
    }
    EXPECT_EQ(shares, alone_shares);
    EXPECT_TRUE(has_sides[0]) << "the first chunk, the largest, holds groups";
    EXPECT_EQ(shares > 0, GetParam());
    auto built = RadiosityRendererFor(*embree_, options_, h);
    auto reused = std::move(*all_).Renderer(*embree_, options_, h);
    ASSERT_TRUE(built.ok()) << built.status();
    ASSERT_TRUE(reused.ok()) << reused.status();
    EXPECT_TRUE(SameBits((*built)->radiosity(), (*reused)->radiosity()));
    EXPECT_EQ((*built)->report().patches, (*reused)->report().patches);
    EXPECT_EQ((*built)->report().estimated_error, (*reused)->report().estimated_error);
    EXPECT_EQ((*built)->mesh().sides().size(), (*reused)->mesh().sides().size());
}

// A solution or a pull of another size, a chunk not linked here and one that does not exist
// are refused with what is wrong named, not read past an end.
TEST_P(RadiositySweepChunksTest, RefusesASolutionPullOrChunkItDoesNotHave) {
    const std::vector<Rgb> h = all_->start();
    const std::vector<Rgb> shorter(h.begin(), h.end() - 1);
    auto renderer = std::move(*all_).Renderer(*embree_, options_, shorter);  // refused: kept
    EXPECT_EQ(renderer.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(renderer.status().message().find("unknowns"), std::string::npos) << renderer.status();
    auto other = alone_[0]->Sweep(1, 0, h);
    EXPECT_EQ(other.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(other.status().message().find("chunk 1 of 3 is not linked"), std::string::npos)
        << other.status();
    EXPECT_FALSE(alone_[0]->Linked(1));
    EXPECT_FALSE(all_->Linked(kChunks));
    const absl::Status beyond = all_->Link(*embree_, kChunks);
    EXPECT_EQ(beyond.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(beyond.message().find("chunk 3 of 3 does not exist"), std::string::npos) << beyond;
    if (!GetParam()) return;
    std::vector<NodeExitance> pulled = all_->Pull(h);
    pulled.pop_back();
    auto swept = all_->Sweep(0, 0, h, pulled);
    EXPECT_EQ(swept.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(swept.status().message().find("a pull of"), std::string::npos) << swept.status();
}

INSTANTIATE_TEST_SUITE_P(FlatAndHierarchical, RadiositySweepChunksTest, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "Hierarchical" : "Flat"; });

}  // namespace
}  // namespace lf
