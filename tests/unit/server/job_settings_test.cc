// Every setting of a submission is checked with the CLI's limits (lf/job/job_spec.h): a job the
// CLI would refuse, forged on the wire, is refused by the coordinator naming the field, before a
// worker could lease it (a radiosity target of 2^40 patches once sent workers into an endless
// loop).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>

#include "lf/core/aov.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/pixel_filter.h"
#include "lf/job/job_spec.h"
#include "lf/server/farm.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

struct BadSetting {
    std::string field;
    std::function<void(JobSpec&)> set;
};

TEST(JobSettingsTest, EveryFieldOutOfRangeIsRefusedNamingIt) {
    const fs::path dir = fs::temp_directory_path() / ("lf_settings_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    FarmOptions options;
    options.data_dir = dir.string();
    absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
    ASSERT_TRUE(farm.ok()) << farm.status();

    const std::vector<BadSetting> bad = {
        {"spp", [](JobSpec& s) { s.plan.spp = 0; }},
        {"spp", [](JobSpec& s) { s.plan.spp = kMaxSpp + 1; }},
        {"tile", [](JobSpec& s) { s.plan.tile = 0; }},
        {"tile", [](JobSpec& s) { s.plan.tile = kMaxFarmTile + 1; }},
        {"tile",
         [](JobSpec& s) {
             s.aovs = kAllAovs;
             s.plan.tile = kMaxFarmAovTile + 1;
         }},
        {"clamp", [](JobSpec& s) { s.clamp = -1; }},
        {"clamp", [](JobSpec& s) { s.clamp = NAN; }},
        {"clamp", [](JobSpec& s) { s.clamp = INFINITY; }},
        {"aovs", [](JobSpec& s) { s.aovs = kKnownAovs + 1; }},
        {"filter",
         [](JobSpec& s) {
             s.scene_options.filter = PixelFilter{PixelFilter::Type::kBox, 2};
         }},
        {"filter",
         [](JobSpec& s) {
             s.scene_options.filter =
                 PixelFilter{PixelFilter::Type::kGaussian, kMaxFilterWidth * 2};
         }},
        {"filter",
         [](JobSpec& s) {
             s.scene_options.filter = PixelFilter{PixelFilter::Type::kBlackmanHarris, NAN};
         }},
        {"passes", [](JobSpec& s) { s.plan.passes = 0; }},
        {"passes", [](JobSpec& s) { s.plan.passes = kMaxPasses + 1; }},
        {"max_depth", [](JobSpec& s) { s.max_depth = -2; }},
        {"max_depth", [](JobSpec& s) { s.max_depth = kMaxDepthLimit + 1; }},
        {"method", [](JobSpec& s) { s.method = "photon"; }},
        {"sampler", [](JobSpec& s) { s.sampler = static_cast<SamplerType>(7); }},
        {"light_strategy", [](JobSpec& s) { s.light_strategy = static_cast<LightStrategy>(7); }},
        {"adaptive.target_error", [](JobSpec& s) { s.adaptive.target_error = 1e-9; }},
        {"adaptive.target_error", [](JobSpec& s) { s.adaptive.target_error = NAN; }},
        {"adaptive.time_limit", [](JobSpec& s) { s.adaptive.time_limit = -1; }},
        {"adaptive.time_limit", [](JobSpec& s) { s.adaptive.time_limit = INFINITY; }},
        {"adaptive.max_spp", [](JobSpec& s) { s.adaptive.max_spp = 1; }},
        {"adaptive.max_spp", [](JobSpec& s) { s.adaptive.max_spp = kMaxSpp + 1; }},
        {"radiosity.patches", [](JobSpec& s) { s.radiosity.patches = 0; }},
        {"radiosity.patches", [](JobSpec& s) { s.radiosity.patches = int64_t(1) << 40; }},
        {"radiosity.patches", [](JobSpec& s) { s.radiosity.patches = kMaxPatchTarget + 1; }},
        {"radiosity.patch_size", [](JobSpec& s) { s.radiosity.patch_size = -1; }},
        {"radiosity.patch_size", [](JobSpec& s) { s.radiosity.patch_size = NAN; }},
        {"radiosity.patch_size", [](JobSpec& s) { s.radiosity.patch_size = INFINITY; }},
        {"radiosity.solver", [](JobSpec& s) { s.radiosity.solver = "newton"; }},
        {"radiosity.tolerance", [](JobSpec& s) { s.radiosity.tolerance = 0; }},
        {"radiosity.tolerance", [](JobSpec& s) { s.radiosity.tolerance = 2; }},
        {"radiosity.max_iterations", [](JobSpec& s) { s.radiosity.max_iterations = 0; }},
        {"radiosity.display", [](JobSpec& s) { s.radiosity.display = "wireframe"; }},
        {"radiosity.sweep_tasks", [](JobSpec& s) { s.radiosity.sweep_tasks = 0; }},
        {"radiosity.sweep_tasks", [](JobSpec& s) { s.radiosity.sweep_tasks = kMaxSweepTasks + 1; }},
        {"radiosity.max_patches", [](JobSpec& s) { s.radiosity.max_patches = -1; }},
        {"radiosity.max_patches",
         [](JobSpec& s) { s.radiosity.max_patches = kMaxRefinedPatches + 1; }},
        {"radiosity.form", [](JobSpec& s) { s.radiosity.form = "progressive"; }},
        {"radiosity.link_error", [](JobSpec& s) { s.radiosity.link_error = 0; }},
        {"radiosity.link_error", [](JobSpec& s) { s.radiosity.link_error = NAN; }},
        {"radiosity.link_error", [](JobSpec& s) { s.radiosity.link_error = 2; }},
        {"radiosity.solver",
         [](JobSpec& s) {
             s.radiosity.form = "hierarchical";
             s.radiosity.solver = "gauss-seidel";
         }},
    };
    for (const BadSetting& b : bad) {
        JobSpec spec;
        spec.method = "radiosity";
        spec.scene = {"scene.json", std::string(64, 'a'), 10};
        b.set(spec);
        const absl::StatusOr<std::string> job = (*farm)->Submit(spec);
        EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument) << b.field;
        EXPECT_EQ(job.status().message().substr(0, b.field.size() + 1), b.field + " ")
            << job.status();
    }
    // The CLI's defaults, and its limits themselves, pass the check.
    JobSpec edge;
    edge.plan = {0, 0, kMaxSpp, kMaxFarmTile, kMaxPasses};
    edge.max_depth = kMaxDepthLimit;
    edge.radiosity.patches = kMaxPatchTarget;
    edge.radiosity.sweep_tasks = kMaxSweepTasks;
    edge.radiosity.max_patches = kMaxRefinedPatches;
    edge.radiosity.form = "hierarchical";
    edge.radiosity.link_error = kMinLinkError;
    edge.clamp = 1e300;
    JobSpec aov_edge = edge;
    aov_edge.aovs = kKnownAovs;
    aov_edge.plan.tile = kMaxFarmAovTile;
    aov_edge.scene_options.filter = PixelFilter{PixelFilter::Type::kGaussian, kMaxFilterWidth};
    EXPECT_TRUE(CheckJobSettings(aov_edge).ok()) << CheckJobSettings(aov_edge);
    EXPECT_TRUE(CheckJobSettings(JobSpec{}).ok()) << CheckJobSettings(JobSpec{});
    EXPECT_EQ(JobSpec{}.sampler, SamplerType::kSobol);
    EXPECT_EQ(JobSpec{}.light_strategy, LightStrategy::kBvh);
    edge.sampler = SamplerType::kIndependent;
    edge.light_strategy = LightStrategy::kPower;
    EXPECT_TRUE(CheckJobSettings(edge).ok()) << CheckJobSettings(edge);
    fs::remove_all(dir);
}

// The illuminance AOV: path (with or without media) and radiosity estimate it; the other
// methods are refused naming the method and the AOV.
TEST(JobSettingsTest, IlluminanceIsRefusedForMethodsWithoutAnEstimate) {
    for (const char* method : {"path", "radiosity"}) {
        JobSpec spec;
        spec.method = method;
        spec.aovs = kAovIlluminance;
        EXPECT_TRUE(CheckJobSettings(spec).ok()) << method << ": " << CheckJobSettings(spec);
    }
    for (const char* method : {"whitted", "light", "bdpt", "ppm"}) {
        JobSpec spec;
        spec.method = method;
        spec.aovs = kAovIlluminance;
        const absl::Status s = CheckJobSettings(spec);
        EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << method;
        EXPECT_NE(s.message().find(method), absl::string_view::npos) << s;
        EXPECT_NE(s.message().find("AOV"), absl::string_view::npos) << s;
    }
    JobSpec whitted;
    whitted.method = "whitted";
    whitted.aovs = kAovIlluminance;
    EXPECT_NE(CheckJobSettings(whitted).message().find("illuminance"), absl::string_view::npos);
}

}  // namespace
}  // namespace lf
