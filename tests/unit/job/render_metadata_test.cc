// The header attributes local mode and the farm both write come from DescribeRender: what it
// adds for each kind of render.
#include "lf/job/render_metadata.h"

#include <gtest/gtest.h>

#include "lf/core/aov.h"
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

// Every header says what its numbers are: radiance in linear Rec.709, with OpenEXR's own
// attributes for viewers that convert to absolute luminance (Y = 1 is 683 cd/m^2).
TEST(RenderMetadata, TheHeaderGivesTheUnitsAndPrimaries) {
    absl::StatusOr<RenderDescription> d =
        DescribeRender(PathMetadata(), EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(d.ok()) << d.status();
    const ExrAttributes& a = d->attributes;
    EXPECT_EQ(std::get<std::string>(a.at("lightfarm.units")),
              "R,G,B: radiance W m^-2 sr^-1, linear Rec.709 RGB");
    const auto& c = std::get<ExrChromaticities>(a.at("chromaticities"));
    // ITU-R BT.709 primaries and the D65 white point.
    EXPECT_EQ(c, (ExrChromaticities{0.64f, 0.33f, 0.30f, 0.60f, 0.15f, 0.06f, 0.3127f, 0.3290f}));
    EXPECT_EQ(std::get<float>(a.at("whiteLuminance")), 683.0f);
}

TEST(RenderMetadata, TheFilterIsAlwaysNamed) {
    RenderMetadata m = PathMetadata();
    absl::StatusOr<RenderDescription> box = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(box.ok()) << box.status();
    EXPECT_EQ(std::get<std::string>(box->attributes.at("lightfarm.filter")), "box");
    m.filter = {PixelFilter::Type::kGaussian, 3};
    absl::StatusOr<RenderDescription> gaussian = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(gaussian.ok()) << gaussian.status();
    EXPECT_EQ(std::get<std::string>(gaussian->attributes.at("lightfarm.filter")), "gaussian 3 px");
    EXPECT_NE(std::get<std::string>(gaussian->attributes.at("lightfarm.channels"))
                  .find("(gaussian 3 px filter)"),
              std::string::npos);
}

TEST(RenderMetadata, AovsAreListedOnlyWhenThereAreAny) {
    RenderMetadata m = PathMetadata();
    absl::StatusOr<RenderDescription> none = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(none.ok()) << none.status();
    EXPECT_FALSE(none->attributes.count("lightfarm.aovs"));
    EXPECT_EQ(std::get<std::string>(none->attributes.at("lightfarm.channels")).find("albedo"),
              std::string::npos);
    m.aovs = kAllAovs;
    absl::StatusOr<RenderDescription> all = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(all.ok()) << all.status();
    EXPECT_EQ(std::get<std::string>(all->attributes.at("lightfarm.aovs")), "albedo,normal,depth");
    const std::string channels = std::get<std::string>(all->attributes.at("lightfarm.channels"));
    for (const char* ch : {"albedo.R,G,B", "normal.X,Y,Z", "depth.Z"}) {
        EXPECT_NE(channels.find(ch), std::string::npos) << ch << " in " << channels;
    }
    EXPECT_NE(std::get<std::string>(all->attributes.at("lightfarm.units")).find("depth.Z"),
              std::string::npos);
    m.aovs = kAovNormal;
    absl::StatusOr<RenderDescription> normal = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(normal.ok()) << normal.status();
    EXPECT_EQ(std::get<std::string>(normal->attributes.at("lightfarm.aovs")), "normal");
}

// --clamp biases the image: the header says so, and that the error estimates leave the bias
// out. Without clamping there is nothing to say.
TEST(RenderMetadata, AClampedImageSaysItIsBiased) {
    RenderMetadata m = PathMetadata();
    absl::StatusOr<RenderDescription> plain = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(plain.ok()) << plain.status();
    EXPECT_FALSE(plain->attributes.count("lightfarm.clamp"));
    EXPECT_FALSE(plain->attributes.count("lightfarm.bias"));
    m.clamp = 10;
    absl::StatusOr<RenderDescription> clamped = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(clamped.ok()) << clamped.status();
    EXPECT_EQ(std::get<double>(clamped->attributes.at("lightfarm.clamp")), 10.0);
    const std::string bias = std::get<std::string>(clamped->attributes.at("lightfarm.bias"));
    EXPECT_EQ(bias.rfind("clamp: ", 0), 0u) << bias;
    EXPECT_NE(bias.find("biased"), std::string::npos) << bias;
    EXPECT_NE(bias.find("lightfarm.estimatedError"), std::string::npos) << bias;
    EXPECT_NE(bias.find("not this bias"), std::string::npos) << bias;
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

// A path-traced image names how its paths sampled lights; radiosity samples none, so its
// header says nothing of it.
TEST(RenderMetadata, LightSamplingIsNamedForPathTracingOnly) {
    RenderMetadata m = PathMetadata();
    for (const LightStrategy strategy : {LightStrategy::kPower, LightStrategy::kBvh}) {
        m.light_strategy = strategy;
        absl::StatusOr<RenderDescription> d = DescribeRender(m, EmptyRenderImage(4, 4), true);
        ASSERT_TRUE(d.ok()) << d.status();
        EXPECT_EQ(std::get<std::string>(d->attributes.at("lightfarm.lightSampling")),
                  LightStrategyName(strategy));
    }
    m.method = "radiosity";
    absl::StatusOr<RenderDescription> radiosity = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(radiosity.ok()) << radiosity.status();
    EXPECT_FALSE(radiosity->attributes.count("lightfarm.lightSampling"));
}

// lightfarm.* names are camelCase, as OpenEXR's own: no snake_case name among them.
TEST(RenderMetadata, AttributeNamesAreCamelCase) {
    for (const char* method : {"path", "radiosity", "light", "bdpt", "ppm", "whitted"}) {
        RenderMetadata m = PathMetadata();
        m.method = method;
        absl::StatusOr<RenderDescription> d = DescribeRender(m, EmptyRenderImage(4, 4), true);
        ASSERT_TRUE(d.ok()) << d.status();
        for (const auto& [name, value] : d->attributes) {
            EXPECT_EQ(name.find('_'), std::string::npos) << method << ": " << name;
        }
    }
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
