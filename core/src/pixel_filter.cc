#include "lf/core/pixel_filter.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <numbers>
#include <utility>

#include "absl/strings/str_cat.h"

namespace lf {

namespace {
constexpr std::array<std::pair<PixelFilter::Type, const char*>, 3> kFilterNames = {{
    {PixelFilter::Type::kBox, "box"},
    {PixelFilter::Type::kGaussian, "gaussian"},
    {PixelFilter::Type::kBlackmanHarris, "blackman-harris"},
}};
// The 4-term Blackman-Harris window (Harris 1978, "minimum 4-term"), centred on 0:
// w(x) = a0 + a1 cos(2 pi x / W) + a2 cos(4 pi x / W) + a3 cos(6 pi x / W) for |x| <= W / 2,
// which is the textbook a0 - a1 cos(2 pi n / N) + ... with n / N = x / W + 1/2.
constexpr std::array<double, 4> kBlackmanHarris = {0.35875, 0.48829, 0.14128, 0.01168};

double GaussianSigma(double width) { return width / 6; }

// The filter's integral from -width/2 to x, over its whole integral: the CDF in closed form.
double FilterCdf(const PixelFilter& filter, double x) {
    const double w = filter.width, r = w / 2;
    switch (filter.type) {
        case PixelFilter::Type::kBox:
            return (x + r) / w;
        case PixelFilter::Type::kGaussian: {
            const double s = GaussianSigma(w) * std::numbers::sqrt2;
            const double edge = std::erf(r / s);
            return (std::erf(x / s) + edge) / (2 * edge);
        }
        case PixelFilter::Type::kBlackmanHarris: {
            double integral = kBlackmanHarris[0] * (x + r);
            for (int k = 1; k < 4; ++k) {
                integral += kBlackmanHarris[size_t(k)] * w / (2 * std::numbers::pi * k) *
                            std::sin(2 * std::numbers::pi * k * x / w);
            }
            return integral / (kBlackmanHarris[0] * w);
        }
    }
    return 0;
}

}  // namespace

const char* PixelFilterTypeName(PixelFilter::Type type) {
    for (const auto& [t, name] : kFilterNames) {
        if (t == type) return name;
    }
    return "unknown";
}

std::optional<PixelFilter::Type> PixelFilterTypeFromName(const std::string& name) {
    for (const auto& [t, n] : kFilterNames) {
        if (name == n) return t;
    }
    return std::nullopt;
}

absl::Status CheckPixelFilter(const PixelFilter& filter) {
    if (filter.type == PixelFilter::Type::kBox) {
        if (filter.width == 1) return absl::OkStatus();
        return absl::InvalidArgumentError(
            absl::StrCat("width ", filter.width, ": the box filter is one pixel wide"));
    }
    if (filter.width >= kMinFilterWidth && filter.width <= kMaxFilterWidth) {
        return absl::OkStatus();
    }
    return absl::InvalidArgumentError(absl::StrCat("width ", filter.width, ": expected ",
                                                   kMinFilterWidth, " to ", kMaxFilterWidth,
                                                   " pixels"));
}

std::string DescribePixelFilter(const PixelFilter& filter) {
    if (filter.type == PixelFilter::Type::kBox) return "box";
    return absl::StrCat(PixelFilterTypeName(filter.type), " ", filter.width, " px");
}

FilterSampler::FilterSampler(const PixelFilter& filter) : radius_(filter.width / 2) {
    assert(CheckPixelFilter(filter).ok());
    if (filter.type == PixelFilter::Type::kBox) return;
    cdf_.resize(kBins + 1);
    for (int i = 1; i < kBins; ++i) {
        cdf_[size_t(i)] = FilterCdf(filter, -radius_ + 2 * radius_ * i / kBins);
    }
    cdf_[0] = 0;
    cdf_[kBins] = 1;  // exactly: u < 1 then always falls in a bin
    guide_.resize(kBins);
    int i = 0;
    for (int j = 0; j < kBins; ++j) {
        while (i + 1 < kBins && cdf_[size_t(i) + 1] <= double(j) / kBins) ++i;
        guide_[size_t(j)] = i;
    }
}

double FilterSampler::Offset(double u) const {
    if (cdf_.empty()) return u - 0.5;
    // The last bin starting at or below u: its CDF interval holds u, and bins of zero mass are
    // never picked.
    size_t i = size_t(guide_[size_t(std::clamp(int(u * kBins), 0, kBins - 1))]);
    while (i + 1 < size_t(kBins) && cdf_[i + 1] <= u) ++i;
    const double mass = cdf_[i + 1] - cdf_[i];
    const double t = mass > 0 ? std::clamp((u - cdf_[i]) / mass, 0.0, 1.0) : 0.5;
    return -radius_ + 2 * radius_ * (double(i) + t) / kBins;
}

}  // namespace lf
