#include "lf/core/image_error.h"

#include <algorithm>
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

// The mean over pixels and channels of ((A - B) / 2)^2.
absl::StatusOr<double> MeanSquaredHalfDifference(const Image& image) {
    double sum = 0;
    size_t n = 0;
    for (const std::string name : {"R", "G", "B"}) {
        absl::StatusOr<const std::vector<float>*> a = RequireChannel(image, "A." + name, "image");
        if (!a.ok()) return a.status();
        absl::StatusOr<const std::vector<float>*> b = RequireChannel(image, "B." + name, "image");
        if (!b.ok()) return b.status();
        for (size_t i = 0; i < (*a)->size(); ++i) {
            const double half = 0.5 * (double((**a)[i]) - (**b)[i]);
            sum += half * half;
            ++n;
        }
    }
    if (n == 0) return absl::InvalidArgumentError("the image has no pixels");
    return sum / n;
}

// One channel of a width x height rectangle, row-major: each pixel's mean and its two halves.
struct ChannelPlanes {
    const float* value;
    const float* a;
    const float* b;
};

// The sum over the rectangle's pixels of ((A - B) / 2)^2 / (p^2 + eps), p = min(R, max(min(A,
// B), mean of the neighbours)), the neighbours (up to 8) inside the rectangle; EstimatedRelMse
// says why.
double SumOfRelativeVariances(int width, int height, const ChannelPlanes& c) {
    double sum = 0;
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            double neighbours = 0;
            int k = 0;
            for (int yy = std::max(0, y - 1); yy <= std::min(height - 1, y + 1); ++yy) {
                for (int xx = std::max(0, x - 1); xx <= std::min(width - 1, x + 1); ++xx) {
                    if (xx == x && yy == y) continue;
                    neighbours += c.value[size_t(yy) * width + xx];
                    ++k;
                }
            }
            const size_t i = size_t(y) * width + x;
            const double own = c.value[i];
            const double steady = std::min(c.a[i], c.b[i]);
            const double p = k > 0 ? std::min(own, std::max(steady, neighbours / k)) : own;
            const double half = 0.5 * (double(c.a[i]) - c.b[i]);
            sum += half * half / (p * p + kRelativeErrorEpsilon);
        }
    }
    return sum;
}

}  // namespace

absl::StatusOr<ImageError> CompareImages(const Image& image, const Image& reference) {
    return CompareImageRegion(image, reference, PixelRect{0, 0, image.width(), image.height()});
}

absl::StatusOr<ImageError> CompareImageRegion(const Image& image, const Image& reference,
                                              const PixelRect& region) {
    if (image.width() != reference.width() || image.height() != reference.height()) {
        return absl::InvalidArgumentError(absl::StrCat("image is ", image.width(), "x",
                                                       image.height(), " but the reference is ",
                                                       reference.width(), "x", reference.height()));
    }
    if (region.width < 0 || region.height < 0 || region.x0 < 0 || region.y0 < 0 ||
        int64_t(region.x0) + region.width > image.width() ||
        int64_t(region.y0) + region.height > image.height()) {
        return absl::InvalidArgumentError(absl::StrCat(
            "region ", region.x0, ",", region.y0, " ", region.width, "x", region.height,
            " leaves the ", image.width(), "x", image.height(), " image"));
    }
    double squared = 0, relative = 0, symmetric = 0;
    size_t n = 0;
    for (const char* name : {"R", "G", "B"}) {
        absl::StatusOr<const std::vector<float>*> x = RequireChannel(image, name, "image");
        if (!x.ok()) return x.status();
        absl::StatusOr<const std::vector<float>*> r = RequireChannel(reference, name, "reference");
        if (!r.ok()) return r.status();
        for (int y = region.y0; y < region.y0 + region.height; ++y) {
            for (int x0 = region.x0; x0 < region.x0 + region.width; ++x0) {
                const size_t i = size_t(y) * size_t(image.width()) + size_t(x0);
                const double xi = (**x)[i], ri = (**r)[i], d = xi - ri;
                squared += d * d;
                relative += d * d / (ri * ri + kRelativeErrorEpsilon);
                symmetric += std::abs(d) / (std::abs(xi) + std::abs(ri) + kRelativeErrorEpsilon);
                ++n;
            }
        }
    }
    if (n == 0) return absl::InvalidArgumentError("the images have no pixels in the region");
    return ImageError{std::sqrt(squared / n), relative / n, symmetric / n};
}

absl::StatusOr<double> EstimatedMse(const Image& image) { return MeanSquaredHalfDifference(image); }

absl::StatusOr<double> EstimatedRelMse(const Image& image) {
    double sum = 0;
    for (const std::string name : {"R", "G", "B"}) {
        absl::StatusOr<const std::vector<float>*> x = RequireChannel(image, name, "image");
        if (!x.ok()) return x.status();
        absl::StatusOr<const std::vector<float>*> a = RequireChannel(image, "A." + name, "image");
        if (!a.ok()) return a.status();
        absl::StatusOr<const std::vector<float>*> b = RequireChannel(image, "B." + name, "image");
        if (!b.ok()) return b.status();
        sum += SumOfRelativeVariances(image.width(), image.height(),
                                      {(*x)->data(), (*a)->data(), (*b)->data()});
    }
    const double n = 3.0 * double(image.width()) * double(image.height());
    if (n == 0) return absl::InvalidArgumentError("the image has no pixels");
    return sum / n;
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
    if (tile.pixels.empty()) return 0;
    const size_t n = tile.pixels.size();
    // Channel c of the means, then of the A and B halves, each n floats.
    std::vector<float> planes(9 * n);
    for (size_t i = 0; i < n; ++i) {
        const PixelSums& p = tile.pixels[i];
        if (p.count[0] == 0 || p.count[1] == 0) return 1;
        const Rgb mean = p.Mean(), a = p.HalfMean(0), b = p.HalfMean(1);
        for (int c = 0; c < 3; ++c) {
            planes[(3 * size_t(c)) * n + i] = mean[c];
            planes[(3 * size_t(c) + 1) * n + i] = a[c];
            planes[(3 * size_t(c) + 2) * n + i] = b[c];
        }
    }
    double relmse = 0;
    for (size_t c = 0; c < 3; ++c) {
        const float* base = planes.data() + 3 * c * n;
        relmse += SumOfRelativeVariances(tile.rect.width, tile.rect.height,
                                         {base, base + n, base + 2 * n});
    }
    return std::sqrt(relmse / (3.0 * double(n)));
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
