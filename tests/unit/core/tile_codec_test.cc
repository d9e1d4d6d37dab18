// Encoded tile sums carry the exact integers: decoding gives back every bit, and anything that
// is not a whole encoded tile is refused with a message instead of being half read.
#include "lf/core/tile_codec.h"

#include <gtest/gtest.h>

#include "lf/core/aov.h"

namespace lf {
namespace {

TileSums MakeTile() {
    TileSums tile(PixelRect{5, 7, 3, 2});
    for (int i = 0; i < 6; ++i) {
        for (uint64_t s = 0; s < 5; ++s) {
            tile.pixels[size_t(i)].Add(s, Rgb(0.1f * float(i) + float(s), -3.5f, 1e9f));
        }
    }
    // Extremes of the 128-bit range, negative ones included.
    tile.pixels[0].sum[1][2] = ExactSum::FromFixed(-(static_cast<__int128>(1) << 126));
    tile.pixels[1].sum[0][0] = ExactSum::FromFixed((static_cast<__int128>(1) << 126) + 12345);
    tile.stats = {30, 123456789012ULL, 2};
    tile.stats.truncated_paths = 7;
    return tile;
}

TEST(TileCodec, RoundTripKeepsEveryBit) {
    const TileSums tile = MakeTile();
    const std::string bytes = EncodeTileSums(tile);
    EXPECT_EQ(bytes.size(), EncodedTileSumsSize(6));
    absl::StatusOr<TileSums> back = DecodeTileSums(bytes);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->rect, tile.rect);
    EXPECT_EQ(back->stats.samples, 30u);
    EXPECT_EQ(back->stats.rays, 123456789012ULL);
    EXPECT_EQ(back->stats.invalid_samples, 2u);
    EXPECT_EQ(back->stats.truncated_paths, 7u);
    for (size_t i = 0; i < tile.pixels.size(); ++i) {
        for (int h = 0; h < 2; ++h) {
            EXPECT_EQ(back->pixels[i].count[h], tile.pixels[i].count[h]);
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(back->pixels[i].sum[h][c], tile.pixels[i].sum[h][c]);
        }
    }
}

TEST(TileCodec, LittleEndianHeader) {
    const std::string bytes = EncodeTileSums(MakeTile());
    EXPECT_EQ(bytes.substr(0, 4), "LFTS");
    EXPECT_EQ(bytes[4], 2);  // version 2, low byte first
    EXPECT_EQ(bytes[8], 5);  // x0
}

// A worker of the previous build sends version 1, without truncated_paths: its tiles still merge.
TEST(TileCodec, Version1TilesDecodeWithNoTruncatedPaths) {
    const TileSums tile = MakeTile();
    std::string v1 = EncodeTileSums(tile);
    constexpr size_t kTruncatedPathsOffset = 4 + 4 + 4 * 4 + 3 * 8;
    v1.erase(kTruncatedPathsOffset, 8);
    v1[4] = 1;
    absl::StatusOr<TileSums> back = DecodeTileSums(v1);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->stats.samples, 30u);
    EXPECT_EQ(back->stats.invalid_samples, 2u);
    EXPECT_EQ(back->stats.truncated_paths, 0u);
    EXPECT_EQ(back->pixels[1].sum[0][0], tile.pixels[1].sum[0][0]);
    EXPECT_EQ(back->pixels[5].count[1], tile.pixels[5].count[1]);
}

// A tile of MakeTile's sums with AOV sums in every pixel, extremes included.
TileSums MakeAovTile(uint32_t aovs) {
    const TileSums plain = MakeTile();
    TileSums tile(plain.rect, aovs);
    tile.pixels = plain.pixels;
    tile.stats = plain.stats;
    for (size_t i = 0; i < tile.aov_pixels.size(); ++i) {
        const FirstHit hit{Rgb(0.25f * float(i), 0.5f, 1), Vec3(-0.6f, 0.8f, float(i) * 1e-3f),
                           1e15f * float(i), 1e5f * float(i) + 0.125f};
        for (int s = 0; s < 3; ++s) tile.aov_pixels[i].Add(aovs, hit);
    }
    if (aovs & kAovNormal) {
        tile.aov_pixels[2].normal[1] = ExactSum::FromFixed(-(static_cast<__int128>(1) << 125));
    }
    return tile;
}

TEST(TileCodec, AovTilesAreVersion3AndKeepEveryBit) {
    for (uint32_t aovs = 1; aovs <= kKnownAovs; ++aovs) {
        const TileSums tile = MakeAovTile(aovs);
        const std::string bytes = EncodeTileSums(tile);
        EXPECT_EQ(bytes[4], 3);
        EXPECT_EQ(bytes.size(), EncodedTileSumsSize(6, aovs));
        absl::StatusOr<TileSums> back = DecodeTileSums(bytes);
        ASSERT_TRUE(back.ok()) << back.status();
        EXPECT_EQ(back->aovs, aovs);
        EXPECT_EQ(back->stats.truncated_paths, 7u);
        ASSERT_EQ(back->aov_pixels.size(), 6u);
        for (size_t i = 0; i < 6; ++i) {
            EXPECT_EQ(back->aov_pixels[i], tile.aov_pixels[i]) << "aovs " << aovs << " pixel " << i;
            EXPECT_EQ(back->pixels[i].sum[1][2], tile.pixels[i].sum[1][2]);
        }
        // Garbage AOV flags and a cut tile are refused.
        std::string zero = bytes, unknown = bytes;
        constexpr size_t kAovOffset = 4 + 4 + 4 * 4 + 4 * 8;
        zero[kAovOffset] = 0;
        unknown[kAovOffset] = char(aovs | 16);
        EXPECT_NE(DecodeTileSums(zero).status().message().find("AOV flags 0"),
                  absl::string_view::npos);
        EXPECT_NE(DecodeTileSums(unknown).status().message().find("AOV flags"),
                  absl::string_view::npos);
        EXPECT_NE(DecodeTileSums(bytes.substr(0, bytes.size() - 4))
                      .status()
                      .message()
                      .find("bytes for a 3x2 tile"),
                  absl::string_view::npos);
    }
}

TEST(TileCodec, GarbageIsRefusedWithAReason) {
    const std::string good = EncodeTileSums(MakeTile());
    struct Case {
        std::string bytes;
        std::string expect;
    };
    std::string bad_version = good, huge = good, negative = good;
    bad_version[4] = 9;
    huge[16] = huge[17] = huge[18] = char(0xff);  // width
    huge[19] = 0x7f;
    negative[23] = char(0x80);  // height < 0
    for (const Case& c : {Case{"", "no LFTS header"}, Case{"hello world, not a tile", "no LFTS"},
                          Case{good.substr(0, good.size() - 1), "bytes for a 3x2 tile"},
                          Case{good + "x", "bytes for a 3x2 tile"}, Case{bad_version, "version 9"},
                          Case{huge, "bad rectangle"}, Case{negative, "bad rectangle"}}) {
        absl::StatusOr<TileSums> tile = DecodeTileSums(c.bytes);
        ASSERT_FALSE(tile.ok());
        EXPECT_EQ(tile.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(tile.status().message().find(c.expect), absl::string_view::npos) << tile.status();
    }
}

}  // namespace
}  // namespace lf
