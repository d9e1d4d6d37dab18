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
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "absl/strings/str_cat.h"
#include "lf/core/image_io.h"

namespace lf {
namespace {

constexpr const char* kRgb[3] = {"R", "G", "B"};

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

int Run(const std::string& a_path, const std::string& b_path, const std::string& png, bool rmse) {
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
        constexpr const char* kHalfA[3] = {"A.R", "A.G", "A.B"};
        constexpr const char* kHalfB[3] = {"B.R", "B.G", "B.B"};
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
    CLI11_PARSE(app, argc, argv);
    return lf::Run(a, b, png, rmse);
}
