// The header attributes local mode and the farm both write come from DescribeRender: what it
// adds for each kind of render.
#include "lf/job/render_metadata.h"

#include <gtest/gtest.h>

#include "lf/job/merge.h"

namespace lf {
namespace {

RenderMetadata PathMetadata() {
    RenderMetadata m;
    m.scene_hash = "abc";
    m.method = "path";
    m.spp = 1;
    m.stats.truncated_paths = 3;
    return m;
}

TEST(RenderMetadata, PathRenderSaysItsTruncatedPathsAndNoRadiosity) {
    absl::StatusOr<RenderDescription> d =
        DescribeRender(PathMetadata(), EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(d.ok()) << d.status();
    EXPECT_EQ(std::get<std::string>(d->attributes.at("lightfarm.truncatedPaths")), "3");
    EXPECT_FALSE(d->estimates);  // one sample per pixel: no A/B halves to compare
    EXPECT_FALSE(d->attributes.count("lightfarm.estimatedError"));
    for (const auto& [name, value] : d->attributes) {
        EXPECT_NE(name.rfind("lightfarm.radiosity.", 0), 0u) << name;
    }
}

TEST(RenderMetadata, ACameraPickedByNameIsNamedAndTheScenesOwnIsNot) {
    RenderMetadata m = PathMetadata();
    absl::StatusOr<RenderDescription> own = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(own.ok()) << own.status();
    EXPECT_FALSE(own->attributes.count("lightfarm.camera"));
    m.camera = "Closeup";
    absl::StatusOr<RenderDescription> picked = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(picked.ok()) << picked.status();
    EXPECT_EQ(std::get<std::string>(picked->attributes.at("lightfarm.camera")), "Closeup");
}

TEST(RenderMetadata, RadiosityFiguresAndSettingsGoIntoTheHeader) {
    RenderMetadata m = PathMetadata();
    m.method = "radiosity";
    RadiosityFigures f;
    f.patches = 300;
    f.unknowns = 320;
    f.iterations = 12;
    f.residual = 5e-5;
    m.radiosity = f;
    absl::StatusOr<RenderDescription> d = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(d.ok()) << d.status();
    const ExrAttributes& a = d->attributes;
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.radiosity.solver")),
              defaults::kRadiositySolver);
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.radiosity.patches")), "300");
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.radiosity.unknowns")), "320");
    EXPECT_EQ(std::get<int>(a.at("lightfarm.radiosity.iterations")), 12);
    EXPECT_EQ(std::get<double>(a.at("lightfarm.radiosity.residual")), 5e-5);
    EXPECT_FALSE(a.count("lightfarm.radiosity.targetError"));  // no refinement asked for
}

// A preview has pixels without samples: no error estimates, whatever the samples per pixel.
TEST(RenderMetadata, ErrorEstimatesOnlyForACompleteImage) {
    RenderMetadata m = PathMetadata();
    m.spp = 4;
    absl::StatusOr<RenderDescription> preview = DescribeRender(m, EmptyRenderImage(4, 4), false);
    ASSERT_TRUE(preview.ok()) << preview.status();
    EXPECT_FALSE(preview->attributes.count("lightfarm.estimatedError"));
}

}  // namespace
}  // namespace lf
