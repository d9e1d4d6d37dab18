#include "lf/core/radiosity_codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace lf {
namespace {

SweepChunkResult Example() {
    SweepChunkResult r;
    r.sweep = 7;
    r.chunk = 2;
    r.sides = 10;
    r.side_begin = 4;
    r.change = {0.1, std::numeric_limits<double>::denorm_min()};
    r.power = {3.0, 1e300};
    r.input = {Rgb(1, 2, 3), Rgb(0.1f, 0.2f, 0.3f), Rgb(-0.0f, 5, 6)};
    r.output = {Rgb(4, 5, 6), Rgb(7, 8, 9), Rgb(1e-40f, 1e38f, 0)};
    return r;
}

TEST(RadiosityCodec, RadiosityRoundTripKeepsEveryBit) {
    const std::vector<Rgb> values = {Rgb(0.1f, 1e-40f, 3e38f), Rgb(-0.0f, 0, 1)};
    absl::StatusOr<std::vector<Rgb>> back = DecodeRadiosity(EncodeRadiosity(values));
    ASSERT_TRUE(back.ok()) << back.status();
    ASSERT_EQ(back->size(), values.size());
    for (size_t i = 0; i < values.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(std::signbit((*back)[i][c]), std::signbit(values[i][c]));
            EXPECT_EQ((*back)[i][c], values[i][c]);
        }
    }
}

// A task's results, one a chunk, back to back: each comes back with every bit, in order.
TEST(RadiosityCodec, SweepResultsRoundTripKeepEveryBit) {
    SweepChunkResult second = Example();
    second.chunk = 5;
    second.side_begin = 0;
    second.change = {2.5};
    second.power = {0.5};
    const std::vector<SweepChunkResult> results = {Example(), second};
    absl::StatusOr<std::vector<SweepChunkResult>> back =
        DecodeSweepResults(EncodeSweepResults(results), 2);
    ASSERT_TRUE(back.ok()) << back.status();
    ASSERT_EQ(back->size(), results.size());
    for (size_t k = 0; k < results.size(); ++k) {
        const SweepChunkResult &r = results[k], &b = (*back)[k];
        EXPECT_EQ(b.sweep, r.sweep);
        EXPECT_EQ(b.chunk, r.chunk);
        EXPECT_EQ(b.sides, r.sides);
        EXPECT_EQ(b.side_begin, r.side_begin);
        EXPECT_EQ(b.change, r.change);
        EXPECT_EQ(b.power, r.power);
        EXPECT_EQ(b.input, r.input);
        EXPECT_EQ(b.output, r.output);
    }
}

TEST(RadiosityCodec, GarbageIsRefusedWithAReason) {
    const std::string good = EncodeSweepResult(Example());
    EXPECT_FALSE(DecodeSweepResults("", 8).ok());
    EXPECT_FALSE(DecodeSweepResults(EncodeRadiosity({}), 8).ok());  // the other kind
    for (const std::string& whole : {good, good + good}) {
        for (size_t cut : {size_t(5), size_t(20), good.size() + 20, whole.size() - 1}) {
            if (cut >= whole.size()) continue;
            absl::StatusOr<std::vector<SweepChunkResult>> r =
                DecodeSweepResults(whole.substr(0, cut), 8);
            EXPECT_FALSE(r.ok()) << cut;
        }
    }
    const absl::Status trailing = DecodeSweepResults(good + "x", 8).status();
    EXPECT_NE(trailing.message().find("after 1 chunk results"), std::string::npos) << trailing;
    // More records than a task has chunks: refused before they are decoded.
    std::string many;
    for (int k = 0; k < 9; ++k) many += good;
    const absl::Status too_many = DecodeSweepResults(many, 8).status();
    EXPECT_NE(too_many.message().find("more than 8 chunk results"), std::string::npos) << too_many;
    EXPECT_TRUE(DecodeSweepResults(many, 9).ok());
    SweepChunkResult outside = Example();
    outside.side_begin = 8;  // 3 sides from 8 overrun the system's 10
    absl::StatusOr<std::vector<SweepChunkResult>> r =
        DecodeSweepResults(EncodeSweepResult(outside), 8);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("outside"), std::string::npos) << r.status();
    // A count far beyond the bytes present is refused before anything is allocated.
    std::string huge = EncodeRadiosity({});
    huge[8] = huge[9] = huge[10] = char(0xff);
    huge[11] = char(0x3f);
    EXPECT_FALSE(DecodeRadiosity(huge).ok());
}

}  // namespace
}  // namespace lf
