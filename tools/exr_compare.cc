// Two renders of the same view (tools/khronos_vs_cycles.sh: lightfarm's and Cycles'): prints
// their mean R, G, B and Rec.709 luminance and the ratios A/B, and optionally writes A and B
// side by side as one sRGB PNG.
//
//   exr_compare A.exr B.exr [--png SIDE.png]
//
// B may have an alpha channel A (Cycles with a transparent film, under a white sky of radiance
// 1): its RGB is then composited over that sky, as A renders it, and the means are taken over
// the pixels B covers fully (alpha >= 0.999), the asset rather than the sky around it.
// Output, one line: "pixels N A r g b lum B r g b lum ratio r g b lum" (ratio nan where B's is 0).
//
//   exr_compare A.exr REFERENCE.exr --rmse      (tools/cycles_bench.sh)
//
// adds " rmse E halves H" to the line: E the root mean square difference A - B over all pixels
// and R, G, B (B over the white sky as above), and H A's own error estimate from lightfarm's
// half-sample channels, sqrt(mean(((A.R - B.R) / 2)^2)) over the same, nan without them.
//
//   exr_compare A.exr REFERENCE.exr --blocks 16   (tools/radiosity_bench.sh)
//
// compares A (e.g. a radiosity render) with a path-traced reference region by region instead: the
// Rec.709 luminance means of N x N blocks, a and b, and b's standard error s from the reference's
// halves, sqrt(sum over the block's pixels of ((A.Y - B.Y) / 2)^2) / pixels. Blocks darker than
// 1e-3 of the reference's mean (windows, the sky) are skipped. Output, one line: "blocks K
// skipped S mean_rel M weighted_rel W worst_rel X at BX,BY mean_beyond_3se E worst_beyond_3se F
// median_se G": |a - b| / b over the blocks (mean, weighted by b, worst), then the part of
// |a - b| beyond 3 s, over b (what the reference's noise cannot explain), and the median of s / b.
// Then A's header attributes lightfarm.radiosity.* (the solve's statistics), one a line:
// "attribute NAME VALUE".
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/image_io.h"

namespace lf {
namespace {

constexpr const char* kRgb[3] = {"R", "G", "B"};
// lightfarm's half-sample estimates (even and odd samples).
constexpr const char* kHalfA[3] = {"A.R", "A.G", "A.B"};
constexpr const char* kHalfB[3] = {"B.R", "B.G", "B.B"};

absl::Status CheckRgb(const Image& image, const std::string& path, const Image& like) {
    for (const char* name : kRgb) {
        const std::vector<float>* channel = image.FindChannel(name);
        if (channel == nullptr || channel->size() != size_t(like.width()) * like.height()) {
            return absl::InvalidArgumentError(absl::StrCat(
                path, ": no channel ", name, " of ", like.width(), "x", like.height(), " pixels"));
        }
    }
    return absl::OkStatus();
}

// B's RGB over a white sky of radiance 1 where its alpha says the film is transparent.
void OverWhite(Image& image) {
    const std::vector<float>* alpha = image.FindChannel("A");
    if (alpha == nullptr) return;
    for (const char* name : kRgb) {
        std::vector<float>& c = image.Channel(name);
        for (size_t i = 0; i < c.size(); ++i) c[i] += 1 - (*alpha)[i];
    }
}

// Mean R, G, B and luminance over the pixels `mask` keeps.
std::array<double, 4> Means(const Image& image, const std::vector<bool>& mask) {
    std::array<double, 4> mean{};
    size_t n = 0;
    for (size_t i = 0; i < mask.size(); ++i) {
        if (!mask[i]) continue;
        ++n;
        for (int c = 0; c < 3; ++c) mean[c] += (*image.FindChannel(kRgb[c]))[i];
    }
    for (int c = 0; c < 3; ++c) mean[c] /= double(n);
    mean[3] = 0.2126 * mean[0] + 0.7152 * mean[1] + 0.0722 * mean[2];
    return mean;
}

// A on the left, B on the right (the same size: CheckRgb).
Image SideBySide(const Image& a, const Image& b) {
    Image out(a.width() + b.width(), a.height());
    for (const char* name : {"R", "G", "B"}) {
        std::vector<float>& dst = out.Channel(name);
        dst.assign(size_t(out.width()) * out.height(), 0.0f);
        for (const Image* src : {&a, &b}) {
            const int x0 = src == &a ? 0 : a.width();
            const std::vector<float>& s = *src->FindChannel(name);
            for (int y = 0; y < src->height(); ++y) {
                for (int x = 0; x < src->width(); ++x) {
                    dst[size_t(y) * out.width() + x0 + x] = s[size_t(y) * src->width() + x];
                }
            }
        }
    }
    return out;
}

// Root mean square of x - y over all pixels and R, G, B, where x and y name the channels.
double Rmse(const Image& a, const char* const x[3], const Image& b, const char* const y[3]) {
    double sum = 0;
    size_t n = 0;
    for (int c = 0; c < 3; ++c) {
        const std::vector<float>* p = a.FindChannel(x[c]);
        const std::vector<float>* q = b.FindChannel(y[c]);
        if (p == nullptr || q == nullptr || p->size() != q->size()) return NAN;
        for (size_t i = 0; i < p->size(); ++i) sum += std::pow(double((*p)[i]) - (*q)[i], 2);
        n += p->size();
    }
    return std::sqrt(sum / double(n));
}

// Rec.709 luminance of the named R, G, B channels; empty if one is missing.
std::vector<double> Luminance(const Image& image, const char* const rgb[3]) {
    const std::vector<float>* c[3];
    for (int k = 0; k < 3; ++k) {
        if ((c[k] = image.FindChannel(rgb[k])) == nullptr) return {};
    }
    std::vector<double> y(c[0]->size());
    for (size_t i = 0; i < y.size(); ++i) {
        y[i] = 0.2126 * (*c[0])[i] + 0.7152 * (*c[1])[i] + 0.0722 * (*c[2])[i];
    }
    return y;
}

// The --blocks line (see the top of the file); B must have its half-sample channels.
absl::Status CompareBlocks(const Image& a, const Image& b, int n) {
    const std::vector<double> ya = Luminance(a, kRgb), yb = Luminance(b, kRgb);
    const std::vector<double> ha = Luminance(b, kHalfA), hb = Luminance(b, kHalfB);
    if (ha.empty() || hb.empty()) {
        return absl::InvalidArgumentError(
            "the reference has no half-sample channels A.R,G,B and B.R,G,B (a path render's)");
    }
    const int w = a.width(), h = a.height();
    double mean_b = 0;
    for (const double v : yb) mean_b += v / double(yb.size());
    int blocks = 0, skipped = 0, worst_x = -1, worst_y = -1;
    double sum_rel = 0, sum_diff = 0, sum_b = 0, worst_rel = 0, sum_beyond = 0, worst_beyond = 0;
    std::vector<double> noise;
    for (int by = 0; by < h; by += n) {
        for (int bx = 0; bx < w; bx += n) {
            double sa = 0, sb = 0, var = 0;
            int pixels = 0;
            for (int y = by; y < std::min(by + n, h); ++y) {
                for (int x = bx; x < std::min(bx + n, w); ++x) {
                    const size_t i = size_t(y) * w + x;
                    sa += ya[i];
                    sb += yb[i];
                    var += std::pow((ha[i] - hb[i]) / 2, 2);
                    ++pixels;
                }
            }
            const double ma = sa / pixels, mb = sb / pixels, se = std::sqrt(var) / pixels;
            if (!(mb > 1e-3 * mean_b)) {
                ++skipped;
                continue;
            }
            ++blocks;
            const double diff = std::abs(ma - mb), rel = diff / mb;
            const double beyond = std::max(0.0, diff - 3 * se) / mb;
            sum_rel += rel;
            sum_diff += diff;
            sum_b += mb;
            sum_beyond += beyond;
            worst_beyond = std::max(worst_beyond, beyond);
            noise.push_back(se / mb);
            if (rel > worst_rel) {
                worst_rel = rel;
                worst_x = bx / n;
                worst_y = by / n;
            }
        }
    }
    if (blocks == 0) return absl::InvalidArgumentError("the reference is black in every block");
    std::nth_element(noise.begin(), noise.begin() + noise.size() / 2, noise.end());
    std::printf(
        "blocks %d skipped %d mean_rel %.4f weighted_rel %.4f worst_rel %.4f at %d,%d "
        "mean_beyond_3se %.4f worst_beyond_3se %.4f median_se %.4f\n",
        blocks, skipped, sum_rel / blocks, sum_diff / sum_b, worst_rel, worst_x, worst_y,
        sum_beyond / blocks, worst_beyond, noise[noise.size() / 2]);
    return absl::OkStatus();
}

int Run(const std::string& a_path, const std::string& b_path, const std::string& png, bool rmse,
        int blocks) {
    absl::StatusOr<ExrFile> a = ReadExr(a_path);
    absl::StatusOr<ExrFile> b = ReadExr(b_path);
    for (const absl::StatusOr<ExrFile>* f : {&a, &b}) {
        if (!f->ok()) {
            std::fprintf(stderr, "exr_compare: %s\n", f->status().ToString().c_str());
            return 1;
        }
    }
    for (const auto& [file, path] : {std::pair{&*a, a_path}, std::pair{&*b, b_path}}) {
        if (absl::Status st = CheckRgb(file->image, path, a->image); !st.ok()) {
            std::fprintf(stderr, "exr_compare: %s\n", st.ToString().c_str());
            return 1;
        }
    }
    if (blocks > 0) {
        if (absl::Status st = CompareBlocks(a->image, b->image, blocks); !st.ok()) {
            std::fprintf(stderr, "exr_compare: %s: %s\n", b_path.c_str(), st.ToString().c_str());
            return 1;
        }
        for (const auto& [name, value] : a->attributes) {
            if (!name.starts_with("lightfarm.radiosity.")) continue;
            std::visit(
                [&name](const auto& v) {
                    using T = std::decay_t<decltype(v)>;
                    if constexpr (std::is_same_v<T, std::string>) {
                        std::printf("attribute %s %s\n", name.c_str(), v.c_str());
                    } else if constexpr (std::is_arithmetic_v<T>) {
                        std::printf("attribute %s %.6g\n", name.c_str(), double(v));
                    }
                },
                value);
        }
        return 0;
    }
    const std::vector<float>* alpha = b->image.FindChannel("A");
    std::vector<bool> mask(size_t(a->image.width()) * a->image.height(), true);
    for (size_t i = 0; alpha != nullptr && i < mask.size(); ++i) mask[i] = (*alpha)[i] >= 0.999f;
    OverWhite(b->image);
    const std::array<double, 4> ma = Means(a->image, mask), mb = Means(b->image, mask);
    std::printf("pixels %zu ", size_t(std::count(mask.begin(), mask.end(), true)));
    std::printf("A");
    for (const double v : ma) std::printf(" %.5g", v);
    std::printf(" B");
    for (const double v : mb) std::printf(" %.5g", v);
    std::printf(" ratio");
    for (int c = 0; c < 4; ++c) std::printf(" %.4f", mb[c] > 0 ? ma[c] / mb[c] : NAN);
    if (rmse) {
        // (A - B) / 2 of the halves: the error of their mean when the halves are independent.
        std::printf(" rmse %.6g halves %.6g", Rmse(a->image, kRgb, b->image, kRgb),
                    Rmse(a->image, kHalfA, a->image, kHalfB) / 2);
    }
    std::printf("\n");
    if (!png.empty()) {
        if (absl::Status s = WritePng(png, SideBySide(a->image, b->image)); !s.ok()) {
            std::fprintf(stderr, "exr_compare: %s\n", s.ToString().c_str());
            return 1;
        }
    }
    return 0;
}

}  // namespace
}  // namespace lf

int main(int argc, char** argv) {
    CLI::App app{
        "Mean R, G, B and luminance of two EXR renders, their ratios A/B, and a "
        "side-by-side sRGB PNG; with --rmse, the RMSE of A against B"};
    std::string a, b, png;
    bool rmse = false;
    app.add_option("a", a, "first image (.exr)")->required();
    app.add_option("b", b, "second image (.exr)")->required();
    app.add_option("--png", png, "write A and B side by side here (8-bit sRGB, clamped)");
    app.add_flag("--rmse", rmse,
                 "also print the RMSE of A against B over all pixels and R, G, B, and A's own "
                 "estimate of it from lightfarm's half-sample channels A.* and B.* (nan without)");
    int blocks = 0;
    app.add_option("--blocks", blocks,
                   "instead: compare A with the path-traced reference B in N x N blocks of "
                   "luminance, against B's standard error from its halves (see the source)")
        ->check(CLI::Range(1, 65536));
    CLI11_PARSE(app, argc, argv);
    return lf::Run(a, b, png, rmse, blocks);
}
