#include "lf/core/image.h"

#include "lf/core/aov.h"

namespace lf {

std::vector<float>& Image::Channel(const std::string& name) {
    auto [it, inserted] = channels_.try_emplace(name);
    if (inserted) it->second.assign(size_t(width_) * height_, 0.0f);
    return it->second;
}

const std::vector<float>* Image::FindChannel(const std::string& name) const {
    auto it = channels_.find(name);
    return it == channels_.end() ? nullptr : &it->second;
}

void Image::SetTile(const TileSums& tile) {
    static const char* kRgb[3] = {"R", "G", "B"};
    std::vector<float>* mean[3];
    std::vector<float>* half[2][3];
    for (int c = 0; c < 3; ++c) {
        mean[c] = &Channel(kRgb[c]);
        half[0][c] = &Channel(std::string("A.") + kRgb[c]);
        half[1][c] = &Channel(std::string("B.") + kRgb[c]);
    }
    std::vector<float>& spp = Channel("spp");
    const PixelRect& r = tile.rect;
    for (int y = r.y0; y < r.y0 + r.height; ++y) {
        for (int x = r.x0; x < r.x0 + r.width; ++x) {
            const PixelSums& p = tile.at(x, y);
            const size_t i = size_t(y) * width_ + x;
            const Rgb m = p.Mean(), a = p.HalfMean(0), b = p.HalfMean(1);
            for (int c = 0; c < 3; ++c) {
                (*mean[c])[i] = m[c];
                (*half[0][c])[i] = a[c];
                (*half[1][c])[i] = b[c];
            }
            spp[i] = float(p.Count());
        }
    }
    if (tile.aovs != 0) SetAovs(tile);
}

void Image::SetAovs(const TileSums& tile) {
    std::vector<float>* albedo[3] = {};
    std::vector<float>* normal[3] = {};
    std::vector<float>* depth = nullptr;
    std::vector<float>* illuminance = nullptr;
    for (int c = 0; c < 3; ++c) {
        if (tile.aovs & kAovAlbedo) albedo[c] = &Channel(kAovAlbedoChannels[c]);
        if (tile.aovs & kAovNormal) normal[c] = &Channel(kAovNormalChannels[c]);
    }
    if (tile.aovs & kAovDepth) depth = &Channel(kAovDepthChannel);
    if (tile.aovs & kAovIlluminance) illuminance = &Channel(kAovIlluminanceChannel);
    const PixelRect& r = tile.rect;
    for (int y = r.y0; y < r.y0 + r.height; ++y) {
        for (int x = r.x0; x < r.x0 + r.width; ++x) {
            const AovSums& a = tile.aov_pixels[tile.Index(x, y)];
            const uint32_t n = tile.at(x, y).Count();
            const size_t i = size_t(y) * width_ + x;
            const Rgb rho = a.Albedo(n);
            const Vec3 ns = a.Normal(n);
            for (int c = 0; c < 3; ++c) {
                if (albedo[c]) (*albedo[c])[i] = rho[c];
                if (normal[c]) (*normal[c])[i] = ns[c];
            }
            if (depth) (*depth)[i] = a.Depth();
            if (illuminance) (*illuminance)[i] = a.Illuminance(n);
        }
    }
}

Rgb Image::Pixel(int x, int y, const std::string& prefix) const {
    const size_t i = size_t(y) * width_ + x;
    Rgb v;
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        const std::vector<float>* ch = FindChannel(prefix + names[c]);
        v[c] = ch ? (*ch)[i] : 0.0f;
    }
    return v;
}

}  // namespace lf
