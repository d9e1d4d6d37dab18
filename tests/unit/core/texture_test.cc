#include "lf/core/texture.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstring>

#include "image_files.h"
#include "lf/core/file_util.h"
#include "lf/core/image_io.h"
#include "lf/core/texture_io.h"
#include "test_dir.h"

namespace lf {
namespace {

// 4 x 2 texels, each channel a distinct value: red counts columns, green rows.
TextureImage Gradient(int channels = 3) {
    TextureImage image;
    image.width = 4;
    image.height = 2;
    image.channels = channels;
    for (int y = 0; y < 2; ++y) {
        for (int x = 0; x < 4; ++x) {
            const uint8_t texel[4] = {uint8_t(40 * x), uint8_t(100 * y), 7, uint8_t(255 - 50 * x)};
            image.texels8.insert(image.texels8.end(), texel, texel + channels);
        }
    }
    return image;
}

TextureRef Nearest(TextureRef::Wrap wrap = TextureRef::Wrap::kRepeat) {
    TextureRef ref;
    ref.image = 0;
    ref.nearest = true;
    ref.wrap_s = ref.wrap_t = wrap;
    return ref;
}

TEST(Texture, UvOriginIsTheTopLeftTexel) {
    const TextureImage image = Gradient();
    // (0, 0) is the top-left corner; v grows downwards, u to the right.
    EXPECT_FLOAT_EQ(Lookup(image, Nearest(), {0.01f, 0.01f}).rgb.g, 0);
    EXPECT_FLOAT_EQ(Lookup(image, Nearest(), {0.01f, 0.99f}).rgb.g, 100 / 255.0f);
    EXPECT_FLOAT_EQ(Lookup(image, Nearest(), {0.99f, 0.01f}).rgb.r, 120 / 255.0f);
    EXPECT_FLOAT_EQ(Lookup(image, Nearest(), {0.3f, 0.2f}).rgb.r, 40 / 255.0f);
}

TEST(Texture, WrapModesAddressTheDocumentedTexels) {
    const TextureImage image = Gradient();
    auto column = [&](TextureRef::Wrap wrap, float u) {
        return int(std::lround(Lookup(image, Nearest(wrap), {u, 0.25f}).rgb.r * 255 / 40));
    };
    // u = 1.1 is texel 4.4: repeat wraps to 0, clamp stays at 3, mirror reflects to 3.
    EXPECT_EQ(column(TextureRef::Wrap::kRepeat, 1.1f), 0);
    EXPECT_EQ(column(TextureRef::Wrap::kClampToEdge, 1.1f), 3);
    EXPECT_EQ(column(TextureRef::Wrap::kMirroredRepeat, 1.1f), 3);
    EXPECT_EQ(column(TextureRef::Wrap::kMirroredRepeat, 1.6f), 1);
    EXPECT_EQ(column(TextureRef::Wrap::kRepeat, -0.1f), 3);
    EXPECT_EQ(column(TextureRef::Wrap::kClampToEdge, -0.1f), 0);
    EXPECT_EQ(column(TextureRef::Wrap::kMirroredRepeat, -0.1f), 0);
    // Far outside, NaN and infinite coordinates still address a texel of the image.
    for (const float u : {1e30f, -1e30f, NAN, INFINITY}) {
        for (const auto wrap : {TextureRef::Wrap::kRepeat, TextureRef::Wrap::kClampToEdge,
                                TextureRef::Wrap::kMirroredRepeat}) {
            const int c = column(wrap, u);
            EXPECT_TRUE(c >= 0 && c <= 3) << u;
            TextureRef bilinear = Nearest(wrap);
            bilinear.nearest = false;
            EXPECT_TRUE(std::isfinite(Lookup(image, bilinear, {u, u}).rgb.r)) << u;
        }
    }
}

TEST(Texture, BilinearIsExactAtTexelCentresAndLinearBetween) {
    const TextureImage image = Gradient();
    TextureRef ref = Nearest(TextureRef::Wrap::kClampToEdge);
    ref.nearest = false;
    // Centres of columns 1 and 2 are at u = 1.5/4 and 2.5/4.
    EXPECT_NEAR(Lookup(image, ref, {1.5f / 4, 0.25f}).rgb.r, 40 / 255.0f, 1e-6);
    EXPECT_NEAR(Lookup(image, ref, {2.5f / 4, 0.25f}).rgb.r, 80 / 255.0f, 1e-6);
    EXPECT_NEAR(Lookup(image, ref, {2.0f / 4, 0.25f}).rgb.r, 60 / 255.0f, 1e-6);
    EXPECT_NEAR(Lookup(image, ref, {1.5f / 4, 0.5f}).rgb.g, 50 / 255.0f, 1e-6);
}

TEST(Texture, ColourTexturesAreSrgbDecodedAndAlphaIsNot) {
    const TextureImage image = Gradient(4);
    TextureRef ref = Nearest();
    ref.srgb = true;
    const Rgba texel = Lookup(image, ref, {0.3f, 0.2f});  // column 1: 40, 0, 7, 205
    const float encoded = 40 / 255.0f;
    EXPECT_NEAR(texel.rgb.r, std::pow((encoded + 0.055f) / 1.055f, 2.4f), 1e-6);
    EXPECT_NEAR(texel.a, 205 / 255.0f, 1e-6);
    ref.srgb = false;
    EXPECT_NEAR(Lookup(image, ref, {0.3f, 0.2f}).rgb.r, encoded, 1e-6);
}

TEST(Texture, TransformFollowsTheExtensionsWorkedExample) {
    // KHR_texture_transform: offset [0, 1], rotation pi/2, scale 0.5 uses the lower-left
    // quadrant of the image, rotated.
    TextureRef ref;
    ref.offset = {0, 1};
    ref.rotation = float(M_PI / 2);
    ref.scale = {0.5f, 0.5f};
    for (const Vec2 corner : {Vec2{0, 0}, Vec2{1, 0}, Vec2{0, 1}, Vec2{1, 1}}) {
        const Vec2 t = TransformUv(ref, corner);
        EXPECT_TRUE(t.x > -1e-6f && t.x < 0.5f + 1e-6f) << t.x;
        EXPECT_TRUE(t.y > 0.5f - 1e-6f && t.y < 1 + 1e-6f) << t.y;
    }
    // The second example flips v: offset [0, 1], scale [1, -1].
    ref = TextureRef{};
    ref.offset = {0, 1};
    ref.scale = {1, -1};
    EXPECT_NEAR(TransformUv(ref, {0.25f, 0.1f}).y, 0.9f, 1e-6);
}

TEST(TextureIo, DecodesPngWithItsChannelsAndSharesTheImage) {
    const TextureImage source = Gradient(4);
    const std::string png = testing::PngBytes(4, 2, 4, source.texels8);
    const auto first = DecodeTexture(png, "a.png");
    ASSERT_TRUE(first.ok()) << first.status();
    EXPECT_EQ((*first)->width, 4);
    EXPECT_EQ((*first)->height, 2);
    EXPECT_EQ((*first)->channels, 4);
    EXPECT_EQ((*first)->texels8, source.texels8);
    // Another name for the same bytes is the same decoded image: loaded once per process.
    const auto second = DecodeTexture(png, "elsewhere/b.png");
    ASSERT_TRUE(second.ok());
    EXPECT_EQ(first->get(), second->get());
}

TEST(TextureIo, DecodesExrAsLinearRadiance) {
    Image exr(3, 2);
    for (int i = 0; i < 6; ++i) {
        exr.Channel("R")[size_t(i)] = 0.5f * float(i);
        exr.Channel("G")[size_t(i)] = 100.0f;  // beyond 8 bits' range: radiance, not a colour
        exr.Channel("B")[size_t(i)] = 0.25f;
    }
    const std::string path = (testing::FreshTestDir("texture_exr") / "sky.exr").string();
    ASSERT_TRUE(WriteExr(path, exr, {}).ok());
    const auto decoded = DecodeTexture(*ReadFile(path), "sky.exr");
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    const TextureImage& image = **decoded;
    EXPECT_TRUE(image.hdr);
    ASSERT_EQ(image.width, 3);
    ASSERT_EQ(image.height, 2);
    // Texel (2, 1) is pixel 5: R = 2.5 (exact in half precision). No sRGB curve applies to
    // radiance, whatever the reference asks.
    const Rgba texel = Texel(image, 2, 1, /*srgb=*/true);
    EXPECT_FLOAT_EQ(texel.rgb.r, 2.5f);
    EXPECT_FLOAT_EQ(texel.rgb.g, 100.0f);
    EXPECT_FLOAT_EQ(texel.rgb.b, 0.25f);
    EXPECT_FLOAT_EQ(texel.a, 1.0f);
}

// Infinities and NaNs in a float image would poison every path that reads them.
TEST(TextureIo, NonFiniteTexelsReadAsZero) {
    Image exr(2, 1);
    exr.Channel("R") = {INFINITY, 1.5f};
    exr.Channel("G") = {NAN, 2.0f};
    exr.Channel("B") = {-INFINITY, 0.5f};
    const std::string path = (testing::FreshTestDir("texture_nan") / "bad.exr").string();
    ASSERT_TRUE(WriteExr(path, exr, {}).ok());
    const auto decoded = DecodeTexture(*ReadFile(path), "bad.exr");
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    const Rgba first = Texel(**decoded, 0, 0, false), second = Texel(**decoded, 1, 0, false);
    EXPECT_EQ(first.rgb, Rgb(0));
    EXPECT_EQ(second.rgb, Rgb(1.5f, 2.0f, 0.5f));
}

TEST(TextureIo, RefusesAnAbsurdSizeFromTheHeaderAlone) {
    // A valid PNG header claiming 100000 x 100000 texels and no data: refused before allocating.
    std::string png = testing::PngBytes(1, 1, 3, {1, 2, 3});
    const auto put32 = [&](size_t at, uint32_t v) {
        for (int i = 0; i < 4; ++i) png[at + size_t(i)] = char(v >> (24 - 8 * i));
    };
    put32(16, 100000);  // IHDR width
    put32(20, 100000);  // IHDR height
    const auto decoded = DecodeTexture(png, "huge.png");
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(decoded.status().message().find("huge.png"), std::string::npos);
    EXPECT_NE(decoded.status().message().find("100000 x 100000"), std::string::npos)
        << decoded.status();
}

// A 1.5 KB EXR whose header declared a 1.4 GB attribute of a type OpenEXR does not know made it
// allocate 1.4 GB (found by tests/fuzz/texture_fuzz; its input is
// tests/fuzz/regressions/texture/): refused from the header, naming the attribute.
TEST(TextureIo, AnExrHeaderDeclaringMoreThanTheFileHoldsIsRefusedBeforeAllocating) {
    Image exr(2, 1);
    for (const char* channel : {"R", "G", "B"}) exr.Channel(channel) = {0.5f, 1.0f};
    const std::string path = (testing::FreshTestDir("texture_exr_header") / "a.exr").string();
    ASSERT_TRUE(WriteExr(path, exr, {}).ok());
    const std::string good = *ReadFile(path);
    // An attribute of a type OpenEXR does not know, declaring 1.4 GB, first in the header.
    const uint32_t size = 0x5200006e;
    std::string huge = good.substr(0, 8) + std::string("bomb\0blob\0", 10) +
                       std::string(reinterpret_cast<const char*>(&size), 4) + good.substr(8);
    const auto decoded = DecodeTexture(huge, "huge.exr");
    ASSERT_FALSE(decoded.ok());
    EXPECT_NE(decoded.status().message().find(
                  "huge.exr: not a readable OpenEXR image: header attribute \"bomb\" declares "
                  "1375731822 bytes"),
              std::string::npos)
        << decoded.status();
}

TEST(TextureIo, GarbageAndTruncatedFilesAreClearErrors) {
    const std::string png = testing::PngBytes(4, 2, 3, std::vector<uint8_t>(24, 9));
    for (const std::string& bytes :
         {std::string("not an image at all"), png.substr(0, png.size() / 2), std::string(),
          std::string("\x76\x2f\x31\x01garbage", 11)}) {
        const auto decoded = DecodeTexture(bytes, "bad.png");
        ASSERT_FALSE(decoded.ok());
        EXPECT_EQ(decoded.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_EQ(decoded.status().message().substr(0, 9), "bad.png: ") << decoded.status();
    }
}

// The bytes tests/fuzz/texture_fuzz found: a 44-byte TGA (a format without a magic number) whose
// header claimed 4071 x 65295 texels, which stb_image allocated and copied (2 GB).
TEST(TextureIo, FormatsBeyondPngJpegHdrAndExrAreRefusedThoughStbKnowsThem) {
    std::string tga("\xa8\x00\x03\x00\x02\x00\xe7\x0fitten by stb_im", 23);
    tga += std::string(21, '\x0f');
    const std::string bmp = std::string("BM") + std::string(60, '\0');
    for (const std::string& bytes : {tga, bmp}) {
        const auto decoded = DecodeTexture(bytes, "odd.png");
        ASSERT_FALSE(decoded.ok());
        EXPECT_EQ(decoded.status().message(),
                  "odd.png: not a PNG, JPEG, HDR or EXR image (unknown signature)");
    }
}

// A JPEG cut after its headers decodes in full with stb_image (it reads zeros past the end): one
// claiming 16384 x 16384 texels in a few hundred bytes is refused before a texel is allocated.
// A PNG chunk claiming more bytes than the file holds is refused before stb_image sees it (a
// fuzzer's 247-byte PNG made it allocate 2 GB); a valid PNG's chunks all fit.
TEST(TextureIo, APngChunkClaimingMoreThanTheFileIsRefusedBeforeDecoding) {
    const TextureImage source = Gradient(4);
    std::string png = testing::PngBytes(4, 2, 4, source.texels8);
    ASSERT_TRUE(DecodeTexture(png, "whole.png").ok());
    const size_t idat = png.find("IDAT");
    ASSERT_NE(idat, std::string::npos);
    png.replace(idat - 4, 4, "\x7f\xff\xff\xff", 4);  // the IDAT chunk's length: 2 GB
    const auto decoded = DecodeTexture(png, "claims.png");
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(decoded.status().message().find("claims.png: PNG chunk at byte " +
                                              std::to_string(idat - 4) + " claims 2147483647"),
              std::string::npos)
        << decoded.status();
}

TEST(TextureIo, ATruncatedJpegClaimingFarMoreTexelsThanItsBytesIsRefused) {
    std::string jpeg;
    const std::vector<uint8_t> texels(8 * 8 * 3, 128);
    ASSERT_TRUE(stbi_write_jpg_to_func(testing::AppendToString, &jpeg, 8, 8, 3, texels.data(), 90));
    const size_t sof = jpeg.find("\xff\xc0");
    const size_t sos = jpeg.find("\xff\xda");
    ASSERT_NE(sof, std::string::npos);
    ASSERT_NE(sos, std::string::npos);
    for (size_t at : {sof + 5, sof + 7}) jpeg.replace(at, 2, "\x40\x00", 2);  // height, width
    jpeg.resize(sos + 14);  // the scan header and nothing of the scan
    const auto decoded = DecodeTexture(jpeg, "cut.jpg");
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(
        decoded.status().message().find("cut.jpg: image of 16384 x 16384 texels in a file of"),
        std::string::npos)
        << decoded.status();
}

// The same for Radiance HDR, whose bound is far lower (at most 16 texels a byte in valid runs).
TEST(TextureIo, ATruncatedHdrClaimingFarMoreTexelsThanItsBytesIsRefused) {
    std::string hdr = testing::HdrBytes(2, 1, {1, 1, 1, 1, 1, 1});
    const size_t size_line = hdr.find("-Y 1 +X 2\n");
    ASSERT_NE(size_line, std::string::npos);
    hdr = hdr.substr(0, size_line) + "-Y 512 +X 512\n";
    const auto decoded = DecodeTexture(hdr, "cut.hdr");
    ASSERT_FALSE(decoded.ok());
    EXPECT_NE(decoded.status().message().find("cut.hdr: image of 512 x 512 texels in a file of"),
              std::string::npos)
        << decoded.status();
}

// The densest valid file of the formats: a 1-bit PNG of one colour, deflated at zlib's best (near
// deflate's limit of 1032:1). The bound on texels a byte must let it through.
TEST(TextureIo, AOneBitPngAtDeflatesLimitIsAccepted) {
    const uint32_t side = 4096;
    // Each row: its filter byte (0, none) and side / 8 bytes of zero bits.
    const std::string raw(size_t(side) * (side / 8 + 1), '\0');
    uLongf packed_size = compressBound(uLong(raw.size()));
    std::string packed(packed_size, '\0');
    ASSERT_EQ(compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size,
                        reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()), 9),
              Z_OK);
    packed.resize(packed_size);
    auto be32 = [](uint32_t v) {
        return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    };
    auto chunk = [&](const std::string& type, const std::string& data) {
        const std::string body = type + data;
        return be32(uint32_t(data.size())) + body +
               be32(uint32_t(
                   crc32(0, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()))));
    };
    // IHDR: width, height, bit depth 1, colour type 0 (grey), deflate, filter 0, no interlace.
    const std::string png =
        std::string("\x89PNG\r\n\x1a\n", 8) +
        chunk("IHDR", be32(side) + be32(side) + std::string("\x01\0\0\0\0", 5)) +
        chunk("IDAT", packed) + chunk("IEND", "");
    EXPECT_GT(double(side) * side / double(png.size()), 7000.0) << png.size() << " bytes";
    const auto decoded = DecodeTexture(png, "dense.png");
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    EXPECT_EQ((*decoded)->width, int(side));
    EXPECT_EQ((*decoded)->texels8.size(), size_t(side) * side);
}

}  // namespace
}  // namespace lf
