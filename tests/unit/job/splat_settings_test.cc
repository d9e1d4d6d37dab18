// The splatting methods' job settings (lf/job/splat_settings.h): which plan each method gets from
// the job's spp, tile and passes; what a job may ask of them (photon settings, no AOVs, no adaptive
// sampling); the kernel settings they map to; and what their EXR header says.
#include "lf/job/splat_settings.h"

#include <gtest/gtest.h>

#include <string>

#include "lf/job/job_spec.h"
#include "lf/job/merge.h"
#include "lf/job/render_metadata.h"

namespace lf {
namespace {

TEST(SplatSettings, MethodsMapToTheirPlanKinds) {
    EXPECT_EQ(SplatPlanKindOf("light"), SplatPlanKind::kLightPaths);
    EXPECT_EQ(SplatPlanKindOf("bdpt"), SplatPlanKind::kCameraAndLight);
    EXPECT_EQ(SplatPlanKindOf("ppm"), SplatPlanKind::kPhotonPasses);
    for (const char* tile_method : {"path", "radiosity", "whitted", "auto", ""}) {
        EXPECT_FALSE(UsesSplatPlan(tile_method)) << tile_method;
        EXPECT_EQ(SplatPlanSettingsOf(tile_method, {8, 8}).status().code(),
                  absl::StatusCode::kInvalidArgument);
    }
}

// spp light paths per pixel-equivalent, in ranges --passes splits, at most 2^18 a task.
TEST(SplatSettings, LightTracingTracesSppPathsPerPixelInPassRanges) {
    absl::StatusOr<SplatPlanSettings> s = SplatPlanSettingsOf("light", {30, 20, 16, 8, 3});
    ASSERT_TRUE(s.ok()) << s.status();
    EXPECT_EQ(s->light_paths, 16u * 30 * 20);
    EXPECT_EQ(s->max_paths_per_task, 3200u);  // ceil(9600 / 3)
    EXPECT_EQ(s->tile, 8);
    absl::StatusOr<std::vector<SplatTask>> tasks = PlanSplatRender(*s);
    ASSERT_TRUE(tasks.ok());
    ASSERT_EQ(tasks->size(), 3u);
    EXPECT_EQ(tasks->back().path_end, 9600u);

    s = SplatPlanSettingsOf("light", {1920, 1080, 16, 32, 1});
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(s->max_paths_per_task, kMaxLightPathsPerTask);
    tasks = PlanSplatRender(*s);
    ASSERT_TRUE(tasks.ok());
    EXPECT_EQ(tasks->size(),
              (16u * 1920 * 1080 + kMaxLightPathsPerTask - 1) / kMaxLightPathsPerTask);
}

TEST(SplatSettings, BdptIsPlannedAsThePathTracer) {
    absl::StatusOr<SplatPlanSettings> s = SplatPlanSettingsOf("bdpt", {30, 20, 16, 8, 4});
    ASSERT_TRUE(s.ok());
    absl::StatusOr<std::vector<SplatTask>> tasks = PlanSplatRender(*s);
    absl::StatusOr<std::vector<RenderTask>> tiles = PlanRender({30, 20, 16, 8, 4});
    ASSERT_TRUE(tasks.ok() && tiles.ok());
    ASSERT_EQ(tasks->size(), tiles->size());
    for (size_t i = 0; i < tasks->size(); ++i) {
        EXPECT_EQ((*tasks)[i].rect.x0, (*tiles)[i].rect.x0);
        EXPECT_EQ((*tasks)[i].sample_end, (*tiles)[i].sample_end);
    }
}

// Photon passes on whole-frame tiles (up to kPpmMaxTile a side), split by --passes.
TEST(SplatSettings, PhotonPassesUseWholeFrameTiles) {
    absl::StatusOr<SplatPlanSettings> s = SplatPlanSettingsOf("ppm", {300, 200, 10, 32, 4});
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(s->tile, 300);
    EXPECT_EQ(s->max_paths_per_task, 3u);  // ceil(10 / 4)
    absl::StatusOr<std::vector<SplatTask>> tasks = PlanSplatRender(*s);
    ASSERT_TRUE(tasks.ok());
    ASSERT_EQ(tasks->size(), 4u);  // passes 0-2, 3-5, 6-8, 9
    EXPECT_EQ((*tasks)[0].rect.Area(), 300 * 200);
    EXPECT_EQ((*tasks)[3].path_begin, 9u);

    s = SplatPlanSettingsOf("ppm", {3000, 500, 10, 32, 1});
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(s->tile, kPpmMaxTile);
}

TEST(SplatSettings, OutOfRangeSizesAreRefused) {
    EXPECT_FALSE(SplatPlanSettingsOf("light", {0, 8, 1}).ok());
    EXPECT_FALSE(SplatPlanSettingsOf("light", {8, 8, 0}).ok());
    EXPECT_FALSE(SplatPlanSettingsOf("ppm", {8, 8, kMaxSpp + 1}).ok());
    EXPECT_FALSE(SplatPlanSettingsOf("bdpt", {8, 8, 4, 8, 0}).ok());
}

TEST(SplatSettings, PhotonSettingsOutsideTheirRangesAreRefusedByName) {
    const struct {
        PhotonSettings ppm;
        const char* field;
    } bad[] = {
        {{0, 0, 0.5}, "ppm.photons_per_pass"},
        {{kMaxPhotonsPerPass + 1, 0, 0.5}, "ppm.photons_per_pass"},
        {{100, -1, 0.5}, "ppm.initial_radius"},
        {{100, std::numeric_limits<double>::infinity(), 0.5}, "ppm.initial_radius"},
        {{100, 0, 0}, "ppm.alpha"},
        {{100, 0, 1}, "ppm.alpha"},
        {{100, 0, std::numeric_limits<double>::quiet_NaN()}, "ppm.alpha"},
    };
    for (const auto& b : bad) {
        JobSpec spec;
        spec.method = "ppm";
        spec.ppm = b.ppm;
        const absl::Status s = CheckJobSettings(spec);
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << b.field;
        EXPECT_EQ(std::string(s.message()).rfind(b.field, 0), 0u) << s;
    }
    EXPECT_TRUE(CheckPhotonSettings({1, 0.25, 0.9}).ok());
}

TEST(SplatSettings, SplatMethodsRefuseAovsAndAdaptiveSampling) {
    for (const char* method : {"light", "bdpt", "ppm"}) {
        JobSpec spec;
        spec.method = method;
        spec.aovs = 1;
        absl::Status s = CheckJobSettings(spec);
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << method;
        EXPECT_NE(std::string(s.message()).find(method), std::string::npos) << s;
        spec.aovs = 0;
        spec.adaptive.target_error = 0.01;
        s = CheckJobSettings(spec);
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << method;
        EXPECT_NE(std::string(s.message()).find("adaptive"), std::string::npos) << s;
    }
}

// A stand-in for lf::SplatRenderSettings with the same members.
struct KernelSettings {
    int max_depth = 5;
    uint64_t seed = 0;
    SamplerType sampler = SamplerType::kSobol;
    double clamp = 0;
    LightStrategy light_strategy = LightStrategy::kBvh;
    uint64_t photons_per_pass = 0;
    double initial_radius = 0;
    double alpha = 0;
};

TEST(SplatSettings, KernelSettingsCarryEveryJobValue) {
    const KernelSettings k = SplatRenderSettingsOf<KernelSettings>(
        7, 42, SamplerType::kIndependent, 3.5, LightStrategy::kPower, {1000, 0.125, 0.75});
    EXPECT_EQ(k.max_depth, 7);
    EXPECT_EQ(k.seed, 42u);
    EXPECT_EQ(k.sampler, SamplerType::kIndependent);
    EXPECT_EQ(k.clamp, 3.5);
    EXPECT_EQ(k.light_strategy, LightStrategy::kPower);
    EXPECT_EQ(k.photons_per_pass, 1000u);
    EXPECT_EQ(k.initial_radius, 0.125);
    EXPECT_EQ(k.alpha, 0.75);
}

std::string Text(const ExrAttributes& a, const std::string& name) {
    auto it = a.find(name);
    return it == a.end() ? "" : std::get<std::string>(it->second);
}

TEST(SplatSettings, HeaderNamesTheMethodAndItsParameters) {
    RenderMetadata m;
    m.scene_hash = "abc";
    m.spp = 4;
    m.max_depth = 6;
    m.method = "light";
    absl::StatusOr<RenderDescription> d = DescribeRender(m, EmptyRenderImage(10, 3), true);
    ASSERT_TRUE(d.ok()) << d.status();
    EXPECT_EQ(Text(d->attributes, "lightfarm.method"), "light");
    EXPECT_EQ(Text(d->attributes, "lightfarm.lightPaths"), "120");
    EXPECT_EQ(Text(d->attributes, "lightfarm.lightPathsPerPixel"), "4");
    EXPECT_EQ(std::get<int>(d->attributes.at("lightfarm.maxDepth")), 6);
    EXPECT_EQ(d->attributes.count("lightfarm.lightSampling"), 0u) << "light tracing samples none";
    EXPECT_EQ(d->attributes.count("lightfarm.bias"), 0u);

    m.method = "bdpt";
    d = DescribeRender(m, EmptyRenderImage(10, 3), true);
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(Text(d->attributes, "lightfarm.lightPaths"), "120");
    EXPECT_EQ(Text(d->attributes, "lightfarm.lightSampling"), "bvh");

    m.method = "ppm";
    m.ppm = {5000, 0, 0.75};
    m.clamp = 2;
    d = DescribeRender(m, EmptyRenderImage(10, 3), true);
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(Text(d->attributes, "lightfarm.ppm.passes"), "4");
    EXPECT_EQ(Text(d->attributes, "lightfarm.ppm.photonsPerPass"), "5000");
    EXPECT_EQ(std::get<double>(d->attributes.at("lightfarm.ppm.alpha")), 0.75);
    EXPECT_EQ(std::get<double>(d->attributes.at("lightfarm.ppm.initialRadius")), 0.0);
    EXPECT_NE(Text(d->attributes, "lightfarm.ppm.radiusSchedule").find("kernel's choice"),
              std::string::npos);
    EXPECT_EQ(d->attributes.count("lightfarm.lightPaths"), 0u);
    // Both biases are named: the clamp's and the radius's.
    const std::string bias = Text(d->attributes, "lightfarm.bias");
    EXPECT_NE(bias.find("clamp"), std::string::npos) << bias;
    EXPECT_NE(bias.find("passes^-0.25"), std::string::npos) << bias;
}

}  // namespace
}  // namespace lf
