// Pixel filters (lf::PixelFilter in scene.h) by name, as the JSON camera's "filter" and the
// `--filter` flag spell them.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"

namespace lf {

// "box", "gaussian", "blackman-harris"
const char* PixelFilterTypeName(PixelFilter::Type type);
std::optional<PixelFilter::Type> PixelFilterTypeFromName(const std::string& name);

// Widths a filter may have: box exactly 1 (the seeds' pixel footprint), the others in
// [kMinFilterWidth, kMaxFilterWidth] pixels.
inline constexpr double kMinFilterWidth = 0.5, kMaxFilterWidth = 16;
// Ok, or InvalidArgument saying what is wrong with the width (without naming where: the caller
// knows whether it is a JSON path or a flag).
absl::Status CheckPixelFilter(const PixelFilter& filter);

// "gaussian 3 px" style text for logs and the EXR header ("box" for the box filter).
std::string DescribePixelFilter(const PixelFilter& filter);

// Filter importance sampling (pbrt-v4's FilterSampler, exact rather than tabulated in 2D): a
// sample's film numbers become its place in the pixel, distributed like the filter, so every
// sample keeps weight 1 and adds to its own pixel only; exact sums stay exact and tiles stay
// independent. Filters are separable, so x and y each go through one 1D inverse CDF: the
// filter's exact CDF (closed form) at kBins + 1 evenly spaced offsets, linear between them (a
// piecewise-constant density with the filter's exact mass in every bin). The table is built
// in double in a fixed order from std::erf and std::sin, the libm the kernels already rely on
// for the same bits on every worker.
class FilterSampler {
  public:
    static constexpr int kBins = 1024;

    // `filter` must pass CheckPixelFilter.
    explicit FilterSampler(const PixelFilter& filter);

    // Where a sample with film numbers u (each in [0, 1)) lands, in pixels from the pixel's
    // top-left corner: u itself for the box filter (so box renders keep their bits), else the
    // pixel centre (0.5, 0.5) plus an offset within +-width/2 drawn from the filter.
    Vec2 Sample(const Vec2& u) const {
        if (cdf_.empty()) return u;
        return {float(0.5 + Offset(u.x)), float(0.5 + Offset(u.y))};
    }

    // The 1D marginal: an offset in [-width/2, width/2] for u in [0, 1) (u - 1/2 for the box).
    double Offset(double u) const;

  private:
    double radius_ = 0.5;
    std::vector<double> cdf_;  // kBins + 1 values from 0 to 1; empty for the box filter
    // A guide table (Devroye's "indexed search"): guide_[j] is the last bin whose CDF value is
    // at most j / kBins, where the search for u in [j, j + 1) / kBins starts; a few steps on
    // from there instead of a binary search's ten unpredictable branches. It finds the bin a
    // binary search finds, so the offsets do not depend on it.
    std::vector<int> guide_;
};

}  // namespace lf
