// Errors of an image against a reference, and the error an image estimates for itself from its
// two half-sample buffers (docs/convergence.md defines each metric).
#pragma once

#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/image.h"

namespace lf {

// Keeps the relative metrics finite where the reference is black; 0.01 is the usual choice
// (Rousselle et al.) and is small against the Cornell box's mean radiance of 0.12.
inline constexpr double kRelativeErrorEpsilon = 0.01;

struct ImageError {
    double rmse = 0;    // sqrt(mean (x - r)^2)
    double relmse = 0;  // mean (x - r)^2 / (r^2 + eps)
    double smape = 0;   // mean |x - r| / (|x| + |r| + eps)
};

// Over every pixel and the R, G, B channels. InvalidArgument when the sizes differ or a
// channel is missing.
absl::StatusOr<ImageError> CompareImages(const Image& image, const Image& reference);
// The same over the pixels of `region` alone (a caustic, a highlight: where methods differ).
// InvalidArgument also when the region is empty or leaves the image.
absl::StatusOr<ImageError> CompareImageRegion(const Image& image, const Image& reference,
                                              const PixelRect& region);

// The image's own estimate of its mean squared error: the mean over pixels and channels of
// ((A - B) / 2)^2, unbiased for the variance of R,G,B when A and B hold equally many samples.
// InvalidArgument without the A.* and B.* channels.
absl::StatusOr<double> EstimatedMse(const Image& image);

// The image's own estimate of its relMSE (CompareImages): the mean over pixels and channels of
// ((A - B) / 2)^2 / (p^2 + kRelativeErrorEpsilon), p the pixel's value as far as its noise
// lets us know it: min(R, max(min(A, B), mean of its up to 8 neighbours)). Each pixel counts by
// its error relative to its own value, so a few bright pixels with a large absolute error (a
// light's edges) weigh no more than any other pixel.
// Why not R itself: R^2 = AB + ((A - B) / 2)^2, so a pixel's term was at most 1 and a firefly
// divided itself away, while the true relMSE divides by the reference's value. With R the
// estimate was 0.2-0.5x the true relMSE below 32 spp (0.03x at 2 spp with caustics), while the
// same numerator over the reference's value is within 0.75-1.2x at every spp (measured,
// docs/convergence.md "Error estimates and plan predictions"). A firefly lands in one half, so
// the other half and the neighbours, which do not hold it, give p; a pixel that is bright in
// both halves (a small highlight) keeps its own value; the outer minimum keeps R where the
// neighbours are brighter (beside a light), which would hide a dim pixel's noise.
// InvalidArgument without the R,G,B, A.* and B.* channels.
absl::StatusOr<double> EstimatedRelMse(const Image& image);

// An image is reported as high variance when either of two estimates says it is not to be
// trusted:
// - its pixels: relMSE (EstimatedRelMse) above 0.01 = 0.1^2, a typical pixel off by more than
//   10 % of its value, where noise is plainly visible. Per pixel, so a light's few half-covered
//   edge pixels do not dominate it as they dominate EstimatedRelativeError;
// - its light: the relative standard error of the image's mean radiance above 5 %. A pixel's
//   relMSE term is at most 1, so a few fireflies carrying much of the light barely move the
//   first test; this one is EstimatedRelativeError / sqrt(pixels x 3), which they dominate.
inline constexpr double kHighVarianceRelMse = 0.01;
inline constexpr double kHighVarianceMeanError = 0.05;

struct VarianceAssessment {
    double relmse = 0;      // EstimatedRelMse
    double mean_error = 0;  // relative standard error of the mean radiance
    bool high = false;
};
absl::StatusOr<VarianceAssessment> AssessVariance(const Image& image);

// Floor of the denominator of relative error estimates, in radiance units (W m^-2 sr^-1): a
// black region is done at once instead of chasing 0/0.
inline constexpr double kRelativeErrorFloor = 1e-3;

// The relative error of a whole image: sqrt(mean over pixels and channels of ((A - B) / 2)^2) /
// (mean radiance + floor), from its R,G,B and A.*, B.* channels. Bright pixels dominate it.
absl::StatusOr<double> EstimatedRelativeError(const Image& image);

// The error a tile estimates for itself, the stopping rule of adaptive sampling: the square root
// of its relMSE estimate (EstimatedRelMse over the tile's pixels, the neighbours taken inside the
// tile, so a tile that is the whole image gives the image's value), each pixel's error relative
// to its own value, as Dammertz et al. 2009 and Cycles normalise per pixel. Normalising by the
// tile's mean instead let a tile's few bright pixels (a light's edge) hide the noise of the
// rest: at equal cost the image's relMSE came out 3x that of uniform sampling (measured,
// docs/convergence.md). 1 when a pixel has fewer than 2 samples (no estimate yet).
double EstimatedTileError(const TileSums& tile);

// Least-squares slope of log(y) against log(x); the points must be positive, at least two,
// with distinct x (InvalidArgument otherwise).
absl::StatusOr<double> LogLogSlope(const std::vector<std::pair<double, double>>& points);

}  // namespace lf
