// Encoded tile sums carry the exact integers: decoding gives back every bit, and anything that
// is not a whole encoded tile is refused with a message instead of being half read.
#include "lf/core/tile_codec.h"

#include <gtest/gtest.h>

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
