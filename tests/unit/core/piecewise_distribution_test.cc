// Piecewise-constant distributions: the CDF inversion lands in the piece whose CDF interval
// holds u, linearly within it; densities are f over its integral; zero pieces are never drawn.
#include "lf/core/piecewise_distribution.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace lf {
namespace {

TEST(PiecewiseConstant1D, InvertsTheCdf) {
    // Pieces [0, 1/4), [1/4, 1/2), [1/2, 3/4), [3/4, 1) of f = 1, 0, 3, 4: integral 2,
    // CDF at the boundaries 0, 1/8, 1/8, 1/2, 1.
    const std::vector<float> f = {1, 0, 3, 4};
    const PiecewiseConstant1D d(f);
    EXPECT_DOUBLE_EQ(d.Integral(), 2);
    const struct {
        float u, x;
        int piece;
        float pdf;
    } cases[] = {{0, 0, 0, 0.5f},
                 {0.0625f, 0.125f, 0, 0.5f},
                 {0.125f, 0.5f, 2, 1.5f},  // skips the empty piece
                 {0.3125f, 0.625f, 2, 1.5f},
                 {0.75f, 0.875f, 3, 2}};
    for (const auto& c : cases) {
        float pdf = 0;
        int piece = -1;
        EXPECT_FLOAT_EQ(d.Sample(c.u, &pdf, &piece), c.x) << c.u;
        EXPECT_EQ(piece, c.piece) << c.u;
        EXPECT_FLOAT_EQ(pdf, c.pdf) << c.u;
    }
    float pdf = 0;
    int piece = -1;
    const float last = d.Sample(std::nextafter(1.0f, 0.0f), &pdf, &piece);
    EXPECT_LT(last, 1);
    EXPECT_EQ(piece, 3);
}

TEST(PiecewiseConstant1D, NothingToSampleHasDensityZero) {
    const std::vector<float> f = {0, 0, -1, NAN};
    const PiecewiseConstant1D d(f);
    EXPECT_EQ(d.Integral(), 0);
    float pdf = 1;
    int piece = -1;
    const float x = d.Sample(0.6f, &pdf, &piece);
    EXPECT_EQ(pdf, 0);
    EXPECT_GE(x, 0);
    EXPECT_LT(x, 1);
}

// Two rows: the marginal picks a row by its integral, the conditional a column within it; the
// density is f / integral, the same where Pdf looks it up.
TEST(PiecewiseConstant2D, SamplesTheMarginalThenTheConditional) {
    const std::vector<float> f = {1, 3,   // row 0: integral 2
                                  0, 2};  // row 1: integral 1
    const PiecewiseConstant2D d(f, 2, 2);
    EXPECT_DOUBLE_EQ(d.Integral(), 1.5);
    float pdf = 0;
    // u.y = 0.5 falls in row 0 (marginal CDF 2/3 at its end), 3/4 of the way through it; in
    // row 0 (CDF 1/4 at the column boundary) u.x = 0.5 is 1/3 of the way through column 1.
    Vec2 uv = d.Sample({0.5f, 0.5f}, &pdf);
    EXPECT_FLOAT_EQ(uv.y, 0.375f);
    EXPECT_FLOAT_EQ(uv.x, 2.0f / 3);
    EXPECT_FLOAT_EQ(pdf, 3 / 1.5f);
    EXPECT_FLOAT_EQ(d.Pdf(uv), pdf);
    uv = d.Sample({0.1f, 0.9f}, &pdf);  // row 1, whose only non-empty column is 1
    EXPECT_GE(uv.y, 0.5f);
    EXPECT_GE(uv.x, 0.5f);
    EXPECT_FLOAT_EQ(pdf, 2 / 1.5f);
    EXPECT_EQ(d.Pdf({0.25f, 0.75f}), 0);
}

}  // namespace
}  // namespace lf
