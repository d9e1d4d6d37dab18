// What a farm worker shares between the chunks it holds (lf::RadiositySweepChunk): one pull of
// each sweep's radiosity for all of them, and a chunk's mesh and cluster tree for the display.
// Both must give the bits of the chunk's own pull and of RadiosityRendererFor.
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

class RadiositySweepChunkTest : public ::testing::TestWithParam<bool> {
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
        for (int c = 0; c < kChunks; ++c) {
            auto chunk = RadiositySweepChunk::Build(*embree_, options_, c, kChunks);
            ASSERT_TRUE(chunk.ok()) << chunk.status();
            chunks_.push_back(std::move(*chunk));
        }
    }

    static constexpr int kChunks = 3;
    Scene scene_;  // outlives embree_, which keeps a reference
    std::unique_ptr<EmbreeScene> embree_;
    RadiosityOptions options_;
    std::vector<std::unique_ptr<RadiositySweepChunk>> chunks_;
};

// Every chunk swept with chunk 0's pull gives what it gives with its own, sweep after sweep, and
// the solution's display from a chunk is RadiosityRendererFor's, report included.
TEST_P(RadiositySweepChunkTest, SharedPullAndChunkMeshGiveTheBitsOfTheirOwn) {
    RadiositySolve solve(kChunks, options_.tolerance, options_.max_iterations);
    std::vector<Rgb> h = chunks_[0]->start();  // the gathered irradiance
    for (;;) {
        const std::vector<NodeExitance> pulled = chunks_[0]->Pull(h);
        EXPECT_EQ(pulled.empty(), !GetParam()) << "the flat method pulls nothing";
        for (int c = 0; c < kChunks; ++c) {
            auto own = chunks_[size_t(c)]->Sweep(solve.sweep(), h);
            auto shared = chunks_[size_t(c)]->Sweep(solve.sweep(), h, pulled);
            ASSERT_TRUE(own.ok()) << own.status();
            ASSERT_TRUE(shared.ok()) << shared.status();
            EXPECT_TRUE(SameBits(own->output, shared->output)) << "chunk " << c;
            EXPECT_EQ(own->change, shared->change);
            ASSERT_TRUE(solve.Add(*shared).ok());
        }
        auto outcome = solve.FinishSweep();
        ASSERT_TRUE(outcome.ok()) << outcome.status();
        h = std::move(outcome->radiosity);
        if (outcome->converged) break;
    }
    auto built = RadiosityRendererFor(*embree_, options_, h);
    auto reused = chunks_[1]->Renderer(*embree_, options_, h);
    ASSERT_TRUE(built.ok()) << built.status();
    ASSERT_TRUE(reused.ok()) << reused.status();
    EXPECT_TRUE(SameBits((*built)->radiosity(), (*reused)->radiosity()));
    EXPECT_EQ((*built)->report().patches, (*reused)->report().patches);
    EXPECT_EQ((*built)->report().estimated_error, (*reused)->report().estimated_error);
    EXPECT_EQ((*built)->mesh().sides().size(), (*reused)->mesh().sides().size());
}

// A solution or a pull of another size is refused with the sizes named, not read past its end.
TEST_P(RadiositySweepChunkTest, RefusesASolutionOrPullOfAnotherSize) {
    const std::vector<Rgb> h = chunks_[0]->start();
    const std::vector<Rgb> shorter(h.begin(), h.end() - 1);
    auto renderer = chunks_[0]->Renderer(*embree_, options_, shorter);
    EXPECT_EQ(renderer.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(renderer.status().message().find("unknowns"), std::string::npos) << renderer.status();
    if (!GetParam()) return;
    std::vector<NodeExitance> pulled = chunks_[0]->Pull(h);
    pulled.pop_back();
    auto swept = chunks_[0]->Sweep(0, h, pulled);
    EXPECT_EQ(swept.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(swept.status().message().find("a pull of"), std::string::npos) << swept.status();
}

INSTANTIATE_TEST_SUITE_P(FlatAndHierarchical, RadiositySweepChunkTest, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "Hierarchical" : "Flat"; });

}  // namespace
}  // namespace lf
