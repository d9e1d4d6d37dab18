// A float image with named channels, the in-memory form of what we write as OpenEXR.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "lf/core/film.h"

namespace lf {

class Image {
  public:
    Image() = default;
    Image(int width, int height) : width_(width), height_(height) {}

    int width() const { return width_; }
    int height() const { return height_; }

    // Creates the channel (zero-filled) on first use.
    std::vector<float>& Channel(const std::string& name);
    const std::vector<float>* FindChannel(const std::string& name) const;
    const std::map<std::string, std::vector<float>>& channels() const { return channels_; }

    // Writes a tile's means: R,G,B and the two half-sample estimates A.R.. and B.R..,
    // plus the per-pixel sample count in `spp`, and the AOV channels of tile.aovs
    // (lf/core/aov.h: albedo.R/G/B, normal.X/Y/Z, depth.Z, illuminance), each a mean as AovSums
    // defines.
    void SetTile(const TileSums& tile);

    Rgb Pixel(int x, int y, const std::string& prefix = "") const;

  private:
    void SetAovs(const TileSums& tile);

    int width_ = 0, height_ = 0;
    std::map<std::string, std::vector<float>> channels_;
};

}  // namespace lf
