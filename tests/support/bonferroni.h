// The z threshold of a two-sided normal test at family-wise level `alpha` over `tests` tests
// (Bonferroni): the statistical render tests compare images block by block with it.
#pragma once

#include <cmath>

namespace lf::testing {

inline double BonferroniZ(int tests, double alpha = 1e-3) {
    double lo = 0, hi = 40;
    for (int i = 0; i < 200; ++i) {
        const double z = (lo + hi) / 2;
        (std::erfc(z / std::sqrt(2.0)) > alpha / tests ? lo : hi) = z;
    }
    return hi;
}

}  // namespace lf::testing
