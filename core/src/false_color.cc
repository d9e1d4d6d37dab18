#include "lf/core/false_color.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "lf/core/aov.h"
#include "lf/core/photometry.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop
#include <stb_image_write.h>

namespace lf {

namespace {

// Viridis (matplotlib's, sRGB) at t = 0, 1/8, ..., 1; linear between them.
constexpr std::array<std::array<uint8_t, 3>, 9> kViridis = {{{68, 1, 84},
                                                             {71, 44, 122},
                                                             {59, 81, 139},
                                                             {44, 113, 142},
                                                             {33, 144, 141},
                                                             {39, 173, 129},
                                                             {92, 200, 99},
                                                             {170, 220, 50},
                                                             {253, 231, 37}}};

constexpr std::array<uint8_t, 3> kInk = {255, 255, 255};

class Canvas {
  public:
    explicit Canvas(Rgb8Picture& picture) : p_(picture) {}
    void Set(int x, int y, const std::array<uint8_t, 3>& c) {
        if (x < 0 || y < 0 || x >= p_.width || y >= p_.height) return;
        std::copy(c.begin(), c.end(), &p_.rgb[(size_t(y) * p_.width + x) * 3]);
    }
    void Fill(int x0, int y0, int x1, int y1, const std::array<uint8_t, 3>& c) {
        for (int y = y0; y < y1; ++y) {
            for (int x = x0; x < x1; ++x) Set(x, y, c);
        }
    }
    // stb_easy_font's quads, axis-aligned rectangles at integer corners for an integer origin.
    void Text(int x, int y, const std::string& text) {
        std::string s = text;
        std::vector<char> quads(64 * 64 * std::max<size_t>(s.size(), 1));
        const int n = stb_easy_font_print(float(x), float(y), s.data(), nullptr, quads.data(),
                                          int(quads.size()));
        for (int q = 0; q < n; ++q) {
            float corner[2][2];  // vertices 0 and 2: opposite corners
            std::memcpy(corner[0], &quads[size_t(q) * 64], 8);
            std::memcpy(corner[1], &quads[size_t(q) * 64 + 32], 8);
            Fill(int(std::lround(corner[0][0])), int(std::lround(corner[0][1])),
                 int(std::lround(corner[1][0])), int(std::lround(corner[1][1])), kInk);
        }
    }

  private:
    Rgb8Picture& p_;
};

int TextWidth(const std::string& text) {
    std::string s = text;
    return stb_easy_font_width(s.data());
}

// A power of ten as the legend writes it: plain from 0.001 to 10000, else 1e5, 1e-4.
std::string DecadeLabel(int exponent) {
    if (exponent >= -3 && exponent <= 4) {
        char buf[16];
        std::snprintf(buf, sizeof buf, "%g", std::pow(10.0, exponent));
        return buf;
    }
    return absl::StrCat("1e", exponent);
}

absl::Status CheckRange(double min, double max) {
    if (!(min > 0) || !(max > min) || !std::isfinite(max)) {
        return absl::InvalidArgumentError(
            absl::StrCat("false colour: the scale ", min, " to ", max,
                         " is not a range of positive finite values with MIN < MAX"));
    }
    return absl::OkStatus();
}

absl::Status MissingIlluminance(const char* why) {
    return absl::FailedPreconditionError(
        absl::StrCat("--false-color lux maps the illuminance channel, which ", why,
                     ": add --aov illuminance (path or radiosity)"));
}

}  // namespace

absl::Status CheckFalseColorSource(const FalseColorSpec& spec, uint32_t aovs) {
    if (spec.unit == FalseColorUnit::kLux && !(aovs & kAovIlluminance)) {
        return MissingIlluminance("the render would not make");
    }
    return absl::OkStatus();
}

absl::StatusOr<FalseColorSpec> ParseFalseColor(std::string_view text) {
    const std::vector<std::string> parts =
        absl::StrSplit(absl::string_view(text.data(), text.size()), ':');
    FalseColorSpec spec;
    if (parts[0] == "lux") {
        spec.unit = FalseColorUnit::kLux;
    } else if (parts[0] == "nits") {
        spec.unit = FalseColorUnit::kNits;
    } else {
        return absl::InvalidArgumentError(absl::StrCat("--false-color ", std::string(text),
                                                       ": unknown unit \"", parts[0],
                                                       "\"; expected lux or nits[:MIN:MAX]"));
    }
    if (parts.size() == 1) return spec;
    double min = 0, max = 0;
    if (parts.size() != 3 || !absl::SimpleAtod(parts[1], &min) ||
        !absl::SimpleAtod(parts[2], &max)) {
        return absl::InvalidArgumentError(absl::StrCat("--false-color ", std::string(text),
                                                       ": expected ", parts[0], " or ", parts[0],
                                                       ":MIN:MAX with numbers MIN and MAX"));
    }
    if (absl::Status s = CheckRange(min, max); !s.ok()) {
        return absl::InvalidArgumentError(
            absl::StrCat("--false-color ", std::string(text), ": ", s.message()));
    }
    spec.range = {min, max};
    return spec;
}

const char* FalseColorUnitLabel(FalseColorUnit unit) {
    return unit == FalseColorUnit::kLux ? "lux" : "cd/m2";
}

std::array<uint8_t, 3> FalseColorRamp(double t) {
    const double x = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * (kViridis.size() - 1);
    const size_t i = std::min(size_t(x), kViridis.size() - 2);
    const double f = x - double(i);
    std::array<uint8_t, 3> c;
    for (size_t k = 0; k < 3; ++k) {
        c[k] = uint8_t(std::lround(kViridis[i][k] * (1 - f) + kViridis[i + 1][k] * f));
    }
    return c;
}

double FalseColorPosition(double value, double min, double max) {
    if (!(value > 0)) return 0;
    return std::clamp(std::log(value / min) / std::log(max / min), 0.0, 1.0);
}

std::pair<double, double> RobustDecadeRange(std::span<const float> values) {
    std::vector<float> positive;
    for (float v : values) {
        if (v > 0 && std::isfinite(v)) positive.push_back(v);
    }
    if (positive.empty()) return {1, 10};
    std::sort(positive.begin(), positive.end());
    const size_t last = positive.size() - 1;
    const double low = positive[size_t(std::floor(0.01 * double(last)))];
    const double high = positive[size_t(std::ceil(0.99 * double(last)))];
    const double min = std::pow(10.0, std::floor(std::log10(low)));
    const double max = std::pow(10.0, std::ceil(std::log10(high)));
    return {min, std::max(max, min * 10)};
}

absl::StatusOr<std::vector<float>> FalseColorValues(const Image& image, FalseColorUnit unit) {
    const size_t n = size_t(image.width()) * image.height();
    if (unit == FalseColorUnit::kLux) {
        const std::vector<float>* lux = image.FindChannel(kAovIlluminanceChannel);
        if (!lux) return MissingIlluminance("the image does not have");
        return *lux;
    }
    std::vector<float> nits(n);
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            nits[size_t(y) * image.width() + x] = Photometric(image.Pixel(x, y));
        }
    }
    return nits;
}

absl::StatusOr<Rgb8Picture> DrawFalseColor(std::span<const float> values, int width, int height,
                                           FalseColorUnit unit, double min, double max) {
    if (width <= 0 || height <= 0 || values.size() != size_t(width) * size_t(height)) {
        return absl::InvalidArgumentError(absl::StrCat(
            "false colour: ", values.size(), " values for a ", width, "x", height, " image"));
    }
    if (absl::Status s = CheckRange(min, max); !s.ok()) return s;
    Rgb8Picture picture{width, height + kFalseColorLegendRows, {}};
    picture.rgb.assign(size_t(picture.width) * picture.height * 3, 0);
    Canvas canvas(picture);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const double v = values[size_t(y) * width + x];
            canvas.Set(x, y, FalseColorRamp(FalseColorPosition(v, min, max)));
        }
    }

    // The legend: bar, unit to its right, ticks and numbers under it.
    const int top = height;
    const std::string unit_label = FalseColorUnitLabel(unit);
    const int bar_x0 = 4, bar_x1 = std::max(bar_x0 + 8, width - 8 - TextWidth(unit_label));
    for (int x = bar_x0; x < bar_x1; ++x) {
        const double t = double(x - bar_x0) / double(bar_x1 - 1 - bar_x0);
        canvas.Fill(x, top + 4, x + 1, top + 14, FalseColorRamp(t));
    }
    canvas.Text(bar_x1 + 4, top + 6, unit_label);
    int free_from = 0;  // numbers left of this would overlap the last one
    const double log_ratio = std::log10(max / min);
    for (int e = int(std::ceil(std::log10(min) - 1e-9));
         e <= int(std::floor(std::log10(max) + 1e-9)); ++e) {
        const double t = (double(e) - std::log10(min)) / log_ratio;
        const int x = bar_x0 + int(std::lround(t * double(bar_x1 - 1 - bar_x0)));
        canvas.Fill(x, top + 14, x + 1, top + 18, kInk);
        const std::string label = DecadeLabel(e);
        const int w = TextWidth(label);
        const int left = std::clamp(x - w / 2, 0, std::max(0, width - w));
        if (left < free_from) continue;
        canvas.Text(left, top + 20, label);
        free_from = left + w + 4;
    }
    return picture;
}

std::string FalseColorPath(const std::string& exr_path) {
    const size_t slash = exr_path.find_last_of('/');
    const size_t dot = exr_path.find_last_of('.');
    const bool has_extension =
        dot != std::string::npos && dot > 0 && (slash == std::string::npos || dot > slash + 1);
    return (has_extension ? exr_path.substr(0, dot) : exr_path) + ".falsecolor.png";
}

absl::Status WriteFalseColorPng(const std::string& path, const Image& image,
                                const FalseColorSpec& spec) {
    absl::StatusOr<std::vector<float>> values = FalseColorValues(image, spec.unit);
    if (!values.ok()) return values.status();
    const auto [min, max] = spec.range ? *spec.range : RobustDecadeRange(*values);
    absl::StatusOr<Rgb8Picture> picture =
        DrawFalseColor(*values, image.width(), image.height(), spec.unit, min, max);
    if (!picture.ok()) return picture.status();
    if (!stbi_write_png(path.c_str(), picture->width, picture->height, 3, picture->rgb.data(),
                        picture->width * 3)) {
        return absl::UnavailableError(path + ": cannot write the false-colour PNG");
    }
    return absl::OkStatus();
}

}  // namespace lf
