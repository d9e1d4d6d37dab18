// Local mode's frame renders (lf::RenderSplatImage): the splat plan's tasks, run on any number of
// threads and split by any --passes and --tile, merge into the same bits, normalised as
// lf/job/splat_merge.h says. The renderer here is a made-up one, a pure function of each light
// path's index and each camera sample, as the contract asks of the real kernels.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "lf/core/camera.h"
#include "lf/core/sampler.h"
#include "lf/job/splat_settings.h"
#include "lf/local/local_executor.h"

namespace lf {
namespace {

constexpr int kWidth = 23, kHeight = 17;

// Light path i splats 0 to 3 values anywhere, over many orders of magnitude (half = i's parity);
// a camera sample adds its own value and, for BDPT, splats its own light subpath. Photon passes
// add one camera value per (pixel, pass) and splat nothing.
class FakeSplatRenderer : public SplatRenderer {
  public:
    explicit FakeSplatRenderer(SplatPlanKind kind) : kind_(kind) {}
    void Render(const SplatWork& work, TileSums& camera, SplatList& splats,
                const std::atomic<bool>*) const override {
        for (uint64_t i = work.path_begin; i < work.path_end && kind_ == SplatPlanKind::kLightPaths;
             ++i) {
            Path(i, int(i & 1), splats);
        }
        for (int y = work.rect.y0; y < work.rect.y0 + work.rect.height; ++y) {
            for (int x = work.rect.x0; x < work.rect.x0 + work.rect.width; ++x) {
                for (uint64_t s = work.sample_begin; s < work.sample_end; ++s) {
                    Sampler u(5, x, y, s);
                    camera.at(x, y).Add(s, Rgb(std::exp(20 * u.Get1D() - 10), 1, float(x)));
                    ++camera.stats.samples;
                    if (kind_ == SplatPlanKind::kCameraAndLight) {
                        Path((uint64_t(y * kWidth + x) << 32) + s, int(s & 1), splats);
                    }
                }
            }
        }
    }

  private:
    static void Path(uint64_t index, int half, SplatList& out) {
        Sampler s(7, 0, 0, index);
        const int n = int(s.Get1D() * 4);
        for (int k = 0; k < n; ++k) {
            const Vec2 p = s.Get2D();
            const float u = s.Get1D();
            out.Add(int(p.x * kWidth), int(p.y * kHeight), half, Rgb(std::exp(30 * u - 15), u, 1));
        }
    }
    SplatPlanKind kind_;
};

Camera TestCamera() {
    CameraSpec spec;
    spec.width = kWidth;
    spec.height = kHeight;
    return Camera(spec, Vec3d());
}

bool SameBits(const Image& a, const Image& b) {
    if (a.width() != b.width() || a.height() != b.height()) return false;
    if (a.channels().size() != b.channels().size()) return false;
    for (const auto& [name, ca] : a.channels()) {
        const std::vector<float>* found = b.FindChannel(name);
        if (found == nullptr) return false;
        const std::vector<float>& cb = *found;
        if (ca.size() != cb.size() ||
            std::memcmp(ca.data(), cb.data(), ca.size() * sizeof(float)) != 0) {
            return false;
        }
    }
    return true;
}

Image Render(const char* method, uint64_t spp, int tile, int passes, int threads) {
    const Camera camera = TestCamera();
    absl::StatusOr<SplatPlanSettings> plan =
        SplatPlanSettingsOf(method, {kWidth, kHeight, spp, tile, passes});
    EXPECT_TRUE(plan.ok()) << plan.status();
    const FakeSplatRenderer renderer(plan->kind);
    RenderSettings settings;
    settings.threads = threads;
    absl::StatusOr<RenderOutput> out = RenderSplatImage(camera, renderer, *plan, settings);
    EXPECT_TRUE(out.ok()) << out.status();
    return out.ok() ? std::move(out->image) : Image();
}

TEST(RenderSplatImage, AnySplitAndThreadCountGivesTheSameBits) {
    for (const char* method : {"light", "bdpt", "ppm"}) {
        const Image one = Render(method, 6, 8, 1, 1);
        ASSERT_GT(one.width(), 0) << method;
        EXPECT_TRUE(SameBits(one, Render(method, 6, 8, 5, 2))) << method;
        EXPECT_TRUE(SameBits(one, Render(method, 6, 16, 3, 3))) << method;
        EXPECT_TRUE(SameBits(one, Render(method, 6, 5, 6, 2))) << method;
    }
}

// Light path i splats 1 onto pixel i mod P, so every pixel gets spp splats of 1 from spp x P
// light paths: splat sum x P / N = 1 exactly, each half alike.
TEST(RenderSplatImage, SplatsAreNormalisedByLightPathsPerPixel) {
    class Uniform : public SplatRenderer {
      public:
        void Render(const SplatWork& work, TileSums&, SplatList& splats,
                    const std::atomic<bool>*) const override {
            for (uint64_t i = work.path_begin; i < work.path_end; ++i) {
                const uint64_t q = i % (kWidth * kHeight);
                splats.Add(int(q % kWidth), int(q / kWidth), int(i & 1), Rgb(1, 2, 3));
            }
        }
    };
    const Camera camera = TestCamera();
    absl::StatusOr<SplatPlanSettings> plan =
        SplatPlanSettingsOf("light", {kWidth, kHeight, 4, 8, 3});
    ASSERT_TRUE(plan.ok()) << plan.status();
    absl::StatusOr<RenderOutput> out = RenderSplatImage(camera, Uniform(), *plan, RenderSettings());
    ASSERT_TRUE(out.ok()) << out.status();
    const struct {
        const char* name;
        float value;
    } expected[] = {{"R", 1}, {"G", 2}, {"B", 3}, {"A.R", 1}, {"B.R", 1}, {"A.B", 3}, {"B.G", 2}};
    for (const auto& [name, value] : expected) {
        const std::vector<float>* c = out->image.FindChannel(name);
        ASSERT_NE(c, nullptr) << name;
        for (float v : *c) ASSERT_FLOAT_EQ(v, value) << name;
    }
}

TEST(RenderSplatImage, RefusesAPlanOfAnotherSize) {
    absl::StatusOr<SplatPlanSettings> plan = SplatPlanSettingsOf("light", {kWidth + 1, kHeight, 1});
    ASSERT_TRUE(plan.ok());
    const FakeSplatRenderer renderer(plan->kind);
    absl::StatusOr<RenderOutput> out =
        RenderSplatImage(TestCamera(), renderer, *plan, RenderSettings());
    EXPECT_EQ(out.status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace lf
