// Which pixels of a rectangle a pass samples (per-pixel adaptive sampling: the pixels not yet
// converged). Bit i of the row-major pixels of `rect` is bit i % 8 of bits[i / 8]; no bits means
// every pixel, so a plan without a mask samples the whole rectangle.
#pragma once

#include <cstdint>
#include <string>

#include "lf/core/film.h"

namespace lf {

struct PixelMask {
    PixelRect rect;
    std::string bits;  // (rect.Area() + 7) / 8 bytes, or none: every pixel

    static size_t Bytes(int64_t pixels) { return size_t((pixels + 7) / 8); }
    // A mask of `r` with no pixel set yet.
    static PixelMask None(const PixelRect& r) { return {r, std::string(Bytes(r.Area()), '\0')}; }
    bool Has(size_t i) const { return bits.empty() || (uint8_t(bits[i / 8]) >> (i % 8)) & 1; }
    bool Has(int x, int y) const {
        return Has(size_t(y - rect.y0) * size_t(rect.width) + size_t(x - rect.x0));
    }
    void Set(size_t i) {  // on a mask with bits
        bits[i / 8] = char(uint8_t(bits[i / 8]) | (1u << (i % 8)));
    }
    int64_t Count() const {
        if (bits.empty()) return rect.Area();
        int64_t n = 0;
        for (const char c : bits) n += __builtin_popcount(uint8_t(c));
        return n;
    }
};

}  // namespace lf
