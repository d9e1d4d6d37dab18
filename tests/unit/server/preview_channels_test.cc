// The views of a result image the dashboard's preview offers: which ones an image has, and each
// as R,G,B (normals remapped, depth scaled by the farthest).
#include "lf/server/preview_channels.h"

#include <gtest/gtest.h>

#include "absl/strings/match.h"

namespace lf {
namespace {

// Two pixels with beauty and every AOV.
Image TwoPixels() {
    Image image(2, 1);
    image.Channel("R") = {0.5f, 1};
    image.Channel("G") = {0.5f, 1};
    image.Channel("B") = {0.5f, 1};
    image.Channel("albedo.R") = {0.2f, 0.8f};
    image.Channel("albedo.G") = {0.2f, 0.8f};
    image.Channel("albedo.B") = {0.2f, 0.8f};
    image.Channel("normal.X") = {-1, 1};
    image.Channel("normal.Y") = {0, 0};
    image.Channel("normal.Z") = {1, 0};
    image.Channel("depth.Z") = {2, 8};
    return image;
}

TEST(PreviewChannels, ListsTheViewsTheImageHasInAFixedOrder) {
    EXPECT_EQ(PreviewChannels(TwoPixels()),
              (std::vector<std::string>{"beauty", "albedo", "normal", "depth"}));
    Image halves = TwoPixels();
    for (const char* c : {"A.R", "A.G", "A.B", "B.R", "B.G"}) halves.Channel(c);
    // B lacks B.B: not a view.
    EXPECT_EQ(PreviewChannels(halves),
              (std::vector<std::string>{"beauty", "A", "albedo", "normal", "depth"}));
}

TEST(PreviewChannels, EachViewIsAnRgbImageWithItsToneCurve) {
    const Image image = TwoPixels();
    absl::StatusOr<ChannelView> beauty = ViewChannel(image, "beauty");
    ASSERT_TRUE(beauty.ok()) << beauty.status();
    EXPECT_EQ(beauty->tone, ToneCurve::kFilmic);
    EXPECT_EQ(*beauty->rgb.FindChannel("R"), (std::vector<float>{0.5f, 1}));

    absl::StatusOr<ChannelView> normal = ViewChannel(image, "normal");
    ASSERT_TRUE(normal.ok());
    EXPECT_EQ(normal->tone, ToneCurve::kClamp);
    EXPECT_EQ(*normal->rgb.FindChannel("R"), (std::vector<float>{0, 1}));
    EXPECT_EQ(*normal->rgb.FindChannel("G"), (std::vector<float>{0.5f, 0.5f}));

    absl::StatusOr<ChannelView> depth = ViewChannel(image, "depth");
    ASSERT_TRUE(depth.ok());
    EXPECT_EQ(*depth->rgb.FindChannel("B"), (std::vector<float>{0.25f, 1}));
    EXPECT_EQ(depth->rgb.channels().size(), 3u);
}

// Illuminance (lux) is the last view, grey scaled by the brightest pixel without the filmic curve.
TEST(PreviewChannels, IlluminanceIsGreyScaledByItsBrightest) {
    Image image = TwoPixels();
    image.Channel("illuminance") = {250, 1000};
    EXPECT_EQ(PreviewChannels(image),
              (std::vector<std::string>{"beauty", "albedo", "normal", "depth", "illuminance"}));
    absl::StatusOr<ChannelView> lux = ViewChannel(image, "illuminance");
    ASSERT_TRUE(lux.ok()) << lux.status();
    EXPECT_EQ(lux->tone, ToneCurve::kClamp);
    for (const char* c : {"R", "G", "B"}) {
        EXPECT_EQ(*lux->rgb.FindChannel(c), (std::vector<float>{0.25f, 1})) << c;
    }
}

TEST(PreviewChannels, AViewTheImageLacksIsNamedWithTheOnesItHas) {
    absl::StatusOr<ChannelView> view = ViewChannel(TwoPixels(), "A");
    ASSERT_FALSE(view.ok());
    EXPECT_TRUE(absl::StrContains(view.status().message(), "\"A\"")) << view.status();
    EXPECT_TRUE(absl::StrContains(view.status().message(), "beauty, albedo, normal, depth"));
}

}  // namespace
}  // namespace lf
