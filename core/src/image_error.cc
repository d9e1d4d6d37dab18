#include "lf/core/image_error.h"

#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"

namespace lf {

namespace {

absl::StatusOr<const std::vector<float>*> RequireChannel(const Image& image,
                                                         const std::string& name,
                                                         const char* which) {
    const std::vector<float>* channel = image.FindChannel(name);
    if (channel == nullptr) {
        return absl::InvalidArgumentError(absl::StrCat(which, " has no channel ", name));
    }
    return channel;
}

// The mean over pixels and channels of ((A - B) / 2)^2, each divided by R^2 + eps if relative.
absl::StatusOr<double> MeanSquaredHalfDifference(const Image& image, bool relative) {
    double sum = 0;
    size_t n = 0;
    for (const std::string name : {"R", "G", "B"}) {
        absl::StatusOr<const std::vector<float>*> a = RequireChannel(image, "A." + name, "image");
        if (!a.ok()) return a.status();
        absl::StatusOr<const std::vector<float>*> b = RequireChannel(image, "B." + name, "image");
        if (!b.ok()) return b.status();
        const std::vector<float>* x = nullptr;
        if (relative) {
            absl::StatusOr<const std::vector<float>*> found = RequireChannel(image, name, "image");
            if (!found.ok()) return found.status();
            x = *found;
        }
        for (size_t i = 0; i < (*a)->size(); ++i) {
            const double half = 0.5 * (double((**a)[i]) - (**b)[i]);
            sum +=
                x ? half * half / (double((*x)[i]) * (*x)[i] + kRelativeErrorEpsilon) : half * half;
            ++n;
        }
    }
    if (n == 0) return absl::InvalidArgumentError("the image has no pixels");
    return sum / n;
}

}  // namespace

absl::StatusOr<ImageError> CompareImages(const Image& image, const Image& reference) {
    if (image.width() != reference.width() || image.height() != reference.height()) {
        return absl::InvalidArgumentError(absl::StrCat("image is ", image.width(), "x",
                                                       image.height(), " but the reference is ",
                                                       reference.width(), "x", reference.height()));
    }
    double squared = 0, relative = 0, symmetric = 0;
    size_t n = 0;
    for (const char* name : {"R", "G", "B"}) {
        absl::StatusOr<const std::vector<float>*> x = RequireChannel(image, name, "image");
        if (!x.ok()) return x.status();
        absl::StatusOr<const std::vector<float>*> r = RequireChannel(reference, name, "reference");
        if (!r.ok()) return r.status();
        for (size_t i = 0; i < (*x)->size(); ++i) {
            const double xi = (**x)[i], ri = (**r)[i], d = xi - ri;
            squared += d * d;
            relative += d * d / (ri * ri + kRelativeErrorEpsilon);
            symmetric += std::abs(d) / (std::abs(xi) + std::abs(ri) + kRelativeErrorEpsilon);
            ++n;
        }
    }
    if (n == 0) return absl::InvalidArgumentError("the images have no pixels");
    return ImageError{std::sqrt(squared / n), relative / n, symmetric / n};
}

absl::StatusOr<double> EstimatedMse(const Image& image) {
    return MeanSquaredHalfDifference(image, /*relative=*/false);
}

absl::StatusOr<double> EstimatedRelMse(const Image& image) {
    return MeanSquaredHalfDifference(image, /*relative=*/true);
}

absl::StatusOr<VarianceAssessment> AssessVariance(const Image& image) {
    absl::StatusOr<double> relmse = EstimatedRelMse(image);
    if (!relmse.ok()) return relmse.status();
    absl::StatusOr<double> error = EstimatedRelativeError(image);
    if (!error.ok()) return error.status();
    VarianceAssessment a;
    a.relmse = *relmse;
    a.mean_error = *error / std::sqrt(3.0 * double(image.width()) * double(image.height()));
    a.high = a.relmse > kHighVarianceRelMse || a.mean_error > kHighVarianceMeanError;
    return a;
}

double EstimatedTileError(const TileSums& tile) {
    double relmse = 0;
    for (const PixelSums& p : tile.pixels) {
        if (p.count[0] == 0 || p.count[1] == 0) return 1;
        const Rgb half = (p.HalfMean(0) - p.HalfMean(1)) * 0.5f, m = p.Mean();
        for (int c = 0; c < 3; ++c) {
            relmse += double(half[c]) * half[c] / (double(m[c]) * m[c] + kRelativeErrorEpsilon);
        }
    }
    const double n = 3.0 * double(tile.pixels.size());
    return n == 0 ? 0 : std::sqrt(relmse / n);
}

absl::StatusOr<double> EstimatedRelativeError(const Image& image) {
    absl::StatusOr<double> mse = EstimatedMse(image);
    if (!mse.ok()) return mse.status();
    double mean = 0;
    size_t n = 0;
    for (const char* name : {"R", "G", "B"}) {
        absl::StatusOr<const std::vector<float>*> x = RequireChannel(image, name, "image");
        if (!x.ok()) return x.status();
        for (float v : **x) mean += v;
        n += (*x)->size();
    }
    return std::sqrt(*mse) / (mean / double(n) + kRelativeErrorFloor);
}

absl::StatusOr<double> LogLogSlope(const std::vector<std::pair<double, double>>& points) {
    if (points.size() < 2) return absl::InvalidArgumentError("a slope needs two points");
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const auto& [x, y] : points) {
        if (!(x > 0) || !(y > 0)) {
            return absl::InvalidArgumentError(
                absl::StrCat("log-log slope of a non-positive point (", x, ", ", y, ")"));
        }
        const double lx = std::log(x), ly = std::log(y);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
    }
    const double n = double(points.size());
    const double denominator = n * sxx - sx * sx;
    if (!(denominator > 1e-12 * n * sxx)) {
        return absl::InvalidArgumentError("log-log slope of points with one x");
    }
    return (n * sxy - sx * sy) / denominator;
}

}  // namespace lf
