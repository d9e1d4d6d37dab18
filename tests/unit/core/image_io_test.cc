#include "lf/core/image_io.h"

#include <gtest/gtest.h>
#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <vector>

namespace lf {
namespace {

std::string TempPath(const std::string& name) {
    return (std::filesystem::temp_directory_path() / ("lf_image_io_" + name)).string();
}

TEST(Exr, RoundTripKeepsChannelsAndAttributes) {
    TileSums tile(PixelRect{0, 0, 3, 2});
    for (int y = 0; y < 2; ++y) {
        for (int x = 0; x < 3; ++x) {
            for (uint64_t s = 0; s < 4; ++s)
                tile.at(x, y).Add(s, Rgb(float(x), float(y), float(s)));
        }
    }
    Image image(3, 2);
    image.SetTile(tile);
    const std::string path = TempPath("roundtrip.exr");
    ASSERT_TRUE(WriteExr(path, image,
                         {{"lightfarm.spp", 4},
                          {"lightfarm.method", std::string("path")},
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
    EXPECT_FLOAT_EQ(file->image.Pixel(2, 1).b, 1.5f);        // mean of 0..3
    EXPECT_FLOAT_EQ(file->image.Pixel(2, 1, "A.").b, 1.0f);  // even samples 0, 2
    std::filesystem::remove(path);
}

// The standard attributes a render's header carries for its units keep their OpenEXR types.
TEST(Exr, ChromaticitiesAndFloatAttributesRoundTrip) {
    const std::string path = TempPath("units.exr");
    Image image(2, 2);
    image.Channel("R")[3] = 1;
    const absl::Status written = WriteExr(
        path, image, {{"chromaticities", kRec709Chromaticities}, {"whiteLuminance", 683.0f}});
    ASSERT_TRUE(written.ok()) << written;
    absl::StatusOr<ExrFile> file = ReadExr(path);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_EQ(std::get<ExrChromaticities>(file->attributes.at("chromaticities")),
              kRec709Chromaticities);
    EXPECT_EQ(std::get<float>(file->attributes.at("whiteLuminance")), 683.0f);
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

// The sRGB transfer curve in double, from IEC 61966-2-1, to 8 bits: what a decoded PNG byte
// must be for a display value v.
int SrgbByte(double v) {
    v = std::clamp(v, 0.0, 1.0);
    const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    return int(std::lround(s * 255));
}

// R,G,B of every pixel of a PNG file, decoded independently of the writer (stb_image).
std::vector<int> DecodePng(const std::string& path, int expected_width) {
    int w = 0, h = 0, channels = 0;
    unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 3);
    EXPECT_NE(data, nullptr) << path;
    if (!data) return {};
    EXPECT_EQ(w, expected_width);
    std::vector<int> out(data, data + size_t(w) * h * 3);
    stbi_image_free(data);
    return out;
}

// One pixel per value, the value in R,G,B alike.
Image Ramp(const std::vector<float>& values) {
    Image image(int(values.size()), 1);
    for (size_t i = 0; i < values.size(); ++i) {
        for (const char* c : {"R", "G", "B"}) image.Channel(c)[i] = values[i];
    }
    return image;
}

const std::vector<float> kRampValues = {0.0f, 0.002f, 0.05f, 0.18f, 0.3f, 0.5f,
                                        0.9f, 1.0f,   1.7f,  6.0f,  -0.4f};

// --tonemap clamp (the default) writes the bytes lightfarm always wrote: the sRGB curve of the
// radiance, clipped to [0, 1].
TEST(Png, ClampIsTheSrgbCurveClipped) {
    const std::string path = TempPath("clamp.png");
    std::vector<float> values = kRampValues;
    values.push_back(std::numeric_limits<float>::quiet_NaN());
    ASSERT_TRUE(WritePng(path, Ramp(values)).ok());
    const std::vector<int> bytes = DecodePng(path, int(values.size()));
    ASSERT_EQ(bytes.size(), values.size() * 3);
    for (size_t i = 0; i < values.size(); ++i) {
        const int expected = std::isnan(values[i]) ? 0 : SrgbByte(values[i]);
        for (int k = 0; k < 3; ++k) EXPECT_EQ(bytes[i * 3 + k], expected) << values[i];
        if (!std::isnan(values[i])) {
            EXPECT_EQ(EncodeSrgb8(values[i]), expected) << values[i];
        }
    }
    std::filesystem::remove(path);
}

// In memory: the same pixels as the file, decoded by stb from the bytes.
TEST(Png, EncodedInMemoryDecodesToTheFilesPixels) {
    const Image image = Ramp(kRampValues);
    const PngOptions options{.exposure = 1, .tone = ToneCurve::kFilmic};
    absl::StatusOr<std::string> png = EncodePng(image, options);
    ASSERT_TRUE(png.ok()) << png.status();
    const std::string path = TempPath("memory.png");
    ASSERT_TRUE(WritePng(path, image, options).ok());
    const std::vector<int> from_file = DecodePng(path, int(kRampValues.size()));
    int w = 0, h = 0, channels = 0;
    unsigned char* data = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png->data()),
                                                int(png->size()), &w, &h, &channels, 3);
    ASSERT_NE(data, nullptr);
    EXPECT_EQ(w, int(kRampValues.size()));
    EXPECT_EQ(h, 1);
    EXPECT_EQ(std::vector<int>(data, data + size_t(w) * h * 3), from_file);
    stbi_image_free(data);
    std::filesystem::remove(path);
}

// --exposure EV multiplies the linear values by 2^EV before encoding: each EV doubles them.
TEST(Png, ExposureDoublesLinearValuesPerEv) {
    const std::string path = TempPath("exposure.png");
    for (double ev : {-2.0, -1.0, 1.0, 2.0, 0.5}) {
        ASSERT_TRUE(WritePng(path, Ramp(kRampValues), {.exposure = ev}).ok());
        const std::vector<int> bytes = DecodePng(path, int(kRampValues.size()));
        ASSERT_EQ(bytes.size(), kRampValues.size() * 3);
        for (size_t i = 0; i < kRampValues.size(); ++i) {
            EXPECT_EQ(bytes[i * 3], SrgbByte(kRampValues[i] * std::exp2(ev)))
                << kRampValues[i] << " at " << ev << " EV";
        }
    }
    std::filesystem::remove(path);
}

TEST(Png, FilmicEncodesTheCurveAfterExposure) {
    const std::string path = TempPath("filmic.png");
    ASSERT_TRUE(
        WritePng(path, Ramp(kRampValues), {.exposure = 1, .tone = ToneCurve::kFilmic}).ok());
    const std::vector<int> bytes = DecodePng(path, int(kRampValues.size()));
    ASSERT_EQ(bytes.size(), kRampValues.size() * 3);
    for (size_t i = 0; i < kRampValues.size(); ++i) {
        const double x = std::max(0.0, 2.0 * kRampValues[i]);
        const double aces = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
        EXPECT_EQ(bytes[i * 3], SrgbByte(aces)) << kRampValues[i];
    }
    // 1.7 and 6.0 (3.4 and 12 after exposure) both clip to white under clamp; filmic keeps 3.4
    // below white.
    EXPECT_LT(bytes[8 * 3], 255);
    std::filesystem::remove(path);
}

}  // namespace
}  // namespace lf
