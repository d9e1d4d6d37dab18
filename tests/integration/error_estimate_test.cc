// The image's own relMSE estimate (EstimatedRelMse, from its A/B halves) against its true
// relMSE against an independent high-spp reference, on a diffuse, a glossy and a caustic scene
// with both samplers, at few and at many samples.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/image_error.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"

namespace lf {
namespace {

constexpr int kResolution = 32;
constexpr uint64_t kReferenceSpp = 2048;
// The band the estimate promises (issue 14), widened by this many standard errors of the
// measured ratio: with 1024 pixels both the truth and the estimate are noisy.
constexpr double kLow = 0.67, kHigh = 1.5, kSigmas = 3;

const std::vector<float>& Channel(const Image& image, const std::string& name) {
    return *image.FindChannel(name);
}

using Case = std::tuple<std::string, SamplerType>;

class ErrorEstimate : public ::testing::TestWithParam<Case> {};

TEST_P(ErrorEstimate, IsWithinTheBandOfTheTrueRelMse) {
    const auto& [name, sampler] = GetParam();
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/" + name + ".json");
    ASSERT_TRUE(scene.ok()) << scene.status();
    scene->camera.width = scene->camera.height = kResolution;
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*scene);
    ASSERT_TRUE(embree.ok()) << embree.status();
    const Camera camera(scene->camera, (*embree)->origin());
    const PathTracer tracer(**embree, -1);
    RenderSettings settings;
    settings.sampler = sampler;
    settings.threads = 2;
    settings.spp = kReferenceSpp;
    settings.seed = 99;  // independent of the images'
    absl::StatusOr<RenderOutput> reference = RenderImage(camera, tracer, settings);
    ASSERT_TRUE(reference.ok()) << reference.status();

    for (uint64_t spp : {16, 256}) {
        settings.spp = spp;
        settings.seed = 1;
        absl::StatusOr<RenderOutput> out = RenderImage(camera, tracer, settings);
        ASSERT_TRUE(out.ok()) << out.status();
        // Per pixel (channels averaged), t: the true relative squared error less the
        // reference's own variance (its A/B estimate); the true relMSE is their mean.
        const size_t n = size_t(kResolution) * kResolution;
        std::vector<double> t(n, 0);
        for (const std::string c : {"R", "G", "B"}) {
            const auto &x = Channel(out->image, c), &r = Channel(reference->image, c);
            const auto &ra = Channel(reference->image, "A." + c),
                       &rb = Channel(reference->image, "B." + c);
            for (size_t i = 0; i < n; ++i) {
                const double d = double(x[i]) - r[i], h = 0.5 * (double(ra[i]) - rb[i]);
                t[i] += (d * d - h * h) / (double(r[i]) * r[i] + kRelativeErrorEpsilon) / 3;
            }
        }
        const double estimated = EstimatedRelMse(out->image).value();
        // The pixels are independent, so the truth's relative standard error is that of a mean
        // of the t; the estimate's is taken as the same and independent of it, so the ratio's
        // is sqrt(2) times it (conservative: the two are positively correlated).
        double mean = 0, sq = 0;
        for (double v : t) {
            mean += v / double(n);
            sq += v * v / double(n);
        }
        const double relative_error =
            std::sqrt(2 * std::max(0.0, sq - mean * mean) / double(n - 1)) / mean;
        const double ratio = estimated / mean;
        std::printf("%s %s %llu spp: estimated %.4g, true %.4g, ratio %.3f +- %.3f\n", name.c_str(),
                    SamplerTypeName(sampler), (unsigned long long)spp, estimated, mean, ratio,
                    ratio * relative_error);
        EXPECT_GE(std::log(ratio), std::log(kLow) - kSigmas * relative_error) << spp << " spp";
        EXPECT_LE(std::log(ratio), std::log(kHigh) + kSigmas * relative_error) << spp << " spp";
    }
}

INSTANTIATE_TEST_SUITE_P(
    DiffuseGlossyCaustic, ErrorEstimate,
    ::testing::Combine(::testing::Values("cornell_box", "glossy_room", "materials"),
                       ::testing::Values(SamplerType::kSobol, SamplerType::kIndependent)),
    [](const ::testing::TestParamInfo<Case>& info) {
        return std::get<0>(info.param) + "_" + SamplerTypeName(std::get<1>(info.param));
    });

}  // namespace
}  // namespace lf
