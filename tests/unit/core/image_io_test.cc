#include "lf/core/image_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace lf {
namespace {

std::string TempPath(const std::string& name) {
    return (std::filesystem::temp_directory_path() / ("lf_image_io_" + name)).string();
}

TEST(Exr, RoundTripKeepsChannelsAndAttributes) {
    TileSums tile(PixelRect{0, 0, 3, 2});
    for (int y = 0; y < 2; ++y) {
        for (int x = 0; x < 3; ++x) {
            for (uint64_t s = 0; s < 4; ++s) tile.at(x, y).Add(s, Rgb(float(x), float(y), float(s)));
        }
    }
    Image image(3, 2);
    image.SetTile(tile);
    const std::string path = TempPath("roundtrip.exr");
    ASSERT_TRUE(WriteExr(path, image, {{"lightfarm.spp", 4}, {"lightfarm.method", std::string("path")},
                                       {"lightfarm.seconds", 1.5}})
                    .ok());
    absl::StatusOr<ExrFile> file = ReadExr(path);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(file->image.width(), 3);
    for (const auto& [name, data] : image.channels()) {
        ASSERT_NE(file->image.FindChannel(name), nullptr) << name;
        EXPECT_EQ(*file->image.FindChannel(name), data) << name;
    }
    EXPECT_EQ(std::get<int>(file->attributes.at("lightfarm.spp")), 4);
    EXPECT_EQ(std::get<std::string>(file->attributes.at("lightfarm.method")), "path");
    EXPECT_EQ(std::get<double>(file->attributes.at("lightfarm.seconds")), 1.5);
    EXPECT_FLOAT_EQ(file->image.Pixel(2, 1).b, 1.5f);      // mean of 0..3
    EXPECT_FLOAT_EQ(file->image.Pixel(2, 1, "A.").b, 1.0f);  // even samples 0, 2
    std::filesystem::remove(path);
}

TEST(Exr, MissingFileIsAClearError) {
    absl::StatusOr<ExrFile> file = ReadExr("/nonexistent/x.exr");
    ASSERT_FALSE(file.ok());
    EXPECT_NE(file.status().message().find("/nonexistent/x.exr"), std::string::npos);
}

TEST(Png, WritesAValidFile) {
    Image image(4, 4);
    image.Channel("R")[0] = 1.0f;
    image.Channel("G")[5] = 0.5f;
    const std::string path = TempPath("preview.png");
    ASSERT_TRUE(WritePng(path, image).ok());
    std::ifstream in(path, std::ios::binary);
    char magic[8];
    in.read(magic, 8);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG");
    std::filesystem::remove(path);
    EXPECT_FALSE(WritePng("/nonexistent/dir/p.png", image).ok());
}

}  // namespace
}  // namespace lf
