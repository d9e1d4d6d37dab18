// Pearson's chi-square test of a histogram against expected counts, for sampling routines whose
// cells are not the (theta, phi) grid of chi_square.h: sub-triangles of an emitter, the lights of
// a light BVH.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include "chi_square.h"

namespace lf::testing {

// Expects `observed` (counts, summing to the sample count) to be drawn from `expected` (counts of
// the same total). Cells with small expected counts are pooled, smallest first; a cell of zero
// expectation must stay empty. `num_tests` (the size of the family of such tests) sets the
// Sidak-corrected level, as in ExpectSamplingMatchesPdf.
inline void ExpectCountsMatch(const std::vector<double>& observed,
                              const std::vector<double>& expected, const std::string& name,
                              int num_tests) {
    ASSERT_EQ(observed.size(), expected.size());
    std::vector<size_t> order(expected.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    double chi2 = 0, pooled_observed = 0, pooled_expected = 0;
    int dof = 0;
    for (size_t i : order) {
        const double e = expected[i], o = observed[i];
        if (e == 0) {
            EXPECT_EQ(o, 0) << name << ": samples in cell " << i << " of zero probability";
        } else if (e < kMinExpected || (pooled_expected > 0 && pooled_expected < kMinExpected)) {
            pooled_observed += o;
            pooled_expected += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            ++dof;
        }
    }
    if (pooled_expected > 0) {
        chi2 += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) /
                pooled_expected;
        ++dof;
    }
    dof -= 1;  // the counts sum to the sample count
    ASSERT_GT(dof, 0) << name;
    const double p_value = ChiSquarePValue(chi2, dof);
    const double level = 1 - std::pow(1 - kSignificance, 1.0 / num_tests);
    std::printf("[chi2] %-28s chi2 %9.2f dof %4d p %.4f\n", name.c_str(), chi2, dof, p_value);
    EXPECT_GT(p_value, level) << name << ": chi2 " << chi2 << " with " << dof << " dof";
}

}  // namespace lf::testing
