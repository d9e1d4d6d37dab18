// Encoded splat lists carry the exact integers: decoding gives back every bit, and anything that
// is not a whole, well-formed list is refused with a message, before any large allocation.
#include "lf/core/splat_codec.h"

#include <gtest/gtest.h>

#include <cstring>

namespace lf {
namespace {

SplatList MakeList() {
    SplatList list(17, 9);
    for (int i = 0; i < 300; ++i) {
        list.Add((i * 7) % 17, (i * 5) % 9, i & 1, Rgb(0.01f * float(i), -2.5f, 1e9f));
    }
    return list;
}

// Overwrites the bytes at `offset` with `v`, little-endian.
void Poke(std::string& bytes, size_t offset, uint64_t v, int size) {
    for (int i = 0; i < size; ++i) bytes[offset + size_t(i)] = char(uint8_t(v >> (8 * i)));
}

constexpr size_t kHeader = 24, kEntry = 53;

TEST(SplatCodec, RoundTripKeepsEveryBit) {
    SplatList list = MakeList();
    // Extremes of the 128-bit range, negative ones included.
    std::vector<SplatEntry> entries = list.entries();
    entries[0].rgb[2] = ExactSum::FromFixed(-(static_cast<__int128>(1) << 126));
    entries[1].rgb[0] = ExactSum::FromFixed((static_cast<__int128>(1) << 126) + 12345);
    SplatList extreme = SplatList::FromCoalesced(17, 9, entries);
    const std::string bytes = EncodeSplatList(extreme);
    EXPECT_EQ(bytes.size(), EncodedSplatListSize(entries.size()));
    absl::StatusOr<SplatList> back = DecodeSplatList(bytes);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->width(), 17);
    EXPECT_EQ(back->height(), 9);
    EXPECT_EQ(back->entries(), entries);
    EXPECT_EQ(EncodeSplatList(*back), bytes);
}

TEST(SplatCodec, EmptyListRoundTrips) {
    SplatList empty(3840, 2160);
    absl::StatusOr<SplatList> back = DecodeSplatList(EncodeSplatList(empty));
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_TRUE(back->entries().empty());
    EXPECT_EQ(back->width(), 3840);
}

// A list restricted to one farm tile fits a gRPC message like the tile's own sums.
TEST(SplatCodec, OneTilesListFitsAMessage) {
    EXPECT_LT(EncodedSplatListSize(2 * 192 * 192), size_t(4) << 20);
}

TEST(SplatCodec, RefusesTruncatedInput) {
    SplatList list = MakeList();
    const std::string bytes = EncodeSplatList(list);
    for (size_t n :
         {size_t(0), size_t(3), size_t(23), kHeader, bytes.size() - 1, bytes.size() - kEntry}) {
        absl::StatusOr<SplatList> back = DecodeSplatList(std::string_view(bytes).substr(0, n));
        EXPECT_EQ(back.status().code(), absl::StatusCode::kInvalidArgument) << n << " bytes";
    }
    absl::StatusOr<SplatList> longer = DecodeSplatList(bytes + "x");
    EXPECT_EQ(longer.status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(SplatCodec, RefusesGarbageAndOtherVersions) {
    EXPECT_FALSE(DecodeSplatList(std::string(200, 'q')).ok());
    SplatList list = MakeList();
    std::string bytes = EncodeSplatList(list);
    std::string tile = bytes;
    std::memcpy(tile.data(), "LFTS", 4);  // a tile, not a splat list
    EXPECT_FALSE(DecodeSplatList(tile).ok());
    std::string version = bytes;
    Poke(version, 4, 2, 4);
    absl::StatusOr<SplatList> v = DecodeSplatList(version);
    EXPECT_FALSE(v.ok());
    EXPECT_NE(v.status().message().find("version 2"), std::string::npos) << v.status();
}

TEST(SplatCodec, RefusesHostileSizesBeforeAllocating) {
    SplatList list = MakeList();
    const std::string bytes = EncodeSplatList(list);
    // Counts whose bytes would overflow or exceed the input: refused, nothing allocated.
    for (uint64_t count : {~uint64_t(0), uint64_t(1) << 60, uint64_t(1) << 40,
                           uint64_t(list.entries().size() + 1)}) {
        std::string hostile = bytes;
        Poke(hostile, 16, count, 8);
        absl::StatusOr<SplatList> back = DecodeSplatList(hostile);
        EXPECT_EQ(back.status().code(), absl::StatusCode::kInvalidArgument) << count;
    }
    // Frames that are empty, negative, or of 2^31 pixels or more.
    for (auto [w, h] : {std::pair{0u, 9u}, {17u, 0u}, {0xffffffffu, 9u}, {65536u, 32768u}}) {
        std::string frame = bytes;
        Poke(frame, 8, w, 4);
        Poke(frame, 12, h, 4);
        EXPECT_FALSE(DecodeSplatList(frame).ok()) << w << "x" << h;
    }
}

TEST(SplatCodec, RefusesBadEntries) {
    SplatList list = MakeList();
    const std::string bytes = EncodeSplatList(list);
    const size_t second = kHeader + kEntry;
    std::string outside = bytes;
    Poke(outside, second, 17 * 9, 4);  // the first pixel past the frame
    EXPECT_FALSE(DecodeSplatList(outside).ok());
    std::string half = bytes;
    Poke(half, second + 4, 2, 1);
    EXPECT_FALSE(DecodeSplatList(half).ok());
    std::string repeated = bytes;  // the second entry a copy of the first
    std::memcpy(repeated.data() + second, bytes.data() + kHeader, kEntry);
    absl::StatusOr<SplatList> r = DecodeSplatList(repeated);
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("entry 1"), std::string::npos) << r.status();
    std::string zero = bytes;
    std::memset(zero.data() + second + 5, 0, 48);
    EXPECT_FALSE(DecodeSplatList(zero).ok());
}

}  // namespace
}  // namespace lf
