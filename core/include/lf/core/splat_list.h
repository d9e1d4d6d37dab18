// Contributions of light paths to pixels anywhere on the image (light tracing, BDPT's t = 1
// strategy): a "splat list". Each contribution is converted to the exact fixed-point sum
// (lf::ExactSum) where it is made, so adding lists in any order, on any machine, gives the same
// bits as adding them in one process.
//
// Memory: an entry is 64 bytes (pixel, half, three 128-bit sums). When its storage is full the
// list coalesces adds to the same (pixel, half) before it grows, and grows to 1.5 times the
// distinct entries, so after `n` adds on a W x H frame its storage holds at most
// max(4096, 1.5 x min(n, 2WH)) entries: bounded by the task's path count x splats per path
// (max depth + 1 for a light tracer), and by the image size only for huge tasks. Figures for a
// 3840x2160 frame (docs/farm.md, "Tasks whose samples land anywhere"): 2^20 light paths of at
// most 6 splats each (max depth 5) make n <= 6.29 M adds, at most 604 MB, in practice far less
// since most vertices are occluded or outside the frame; 2^18 paths at most 151 MB; a dense
// full-frame layer takes 8.3 M px x 2 halves x 3 x 16 B = 796 MB whatever the task's size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "lf/core/film.h"
#include "lf/core/rgb.h"

namespace lf {

struct SplatEntry {
    uint32_t pixel = 0;  // y * width + x of the frame
    uint8_t half = 0;    // 0 (A) or 1 (B): the parity of the light path's index
    ExactSum rgb[3];

    bool operator==(const SplatEntry&) const = default;
};

class SplatList {
  public:
    SplatList() = default;
    // A list for a width x height frame (width * height below 2^31).
    SplatList(int width, int height) : width_(width), height_(height) {}

    int width() const { return width_; }
    int height() const { return height_; }

    // Adds `value` to pixel (x, y)'s half `half` (the parity of the light path's index, so the
    // halves stay two independent estimates). Non-finite values are the caller's to reject; the
    // value is clamped like every ExactSum::Add. (x, y) must lie in the frame.
    void Add(int x, int y, int half, const Rgb& value);
    // Adds every entry of `other` (the same frame size).
    SplatList& operator+=(const SplatList& other);

    // Sorts by (pixel, half) and adds up entries of the same (pixel, half), dropping those whose
    // sums are all zero. Cheap when the list is already coalesced.
    void Coalesce();
    // The entries, coalesced: sorted by (pixel, half), one per pair, none all zero.
    const std::vector<SplatEntry>& entries() {
        Coalesce();
        return entries_;
    }
    bool coalesced() const { return coalesced_size_ == entries_.size(); }

    // The entries as they stand (coalesced or not); for the codec and for tests.
    const std::vector<SplatEntry>& raw_entries() const { return entries_; }
    // Bytes of the entries' storage (capacity, not size).
    size_t MemoryBytes() const { return entries_.capacity() * sizeof(SplatEntry); }

    // Replaces the entries; the caller (the decoder) has checked they are coalesced.
    static SplatList FromCoalesced(int width, int height, std::vector<SplatEntry> entries);

    // The entries whose pixels lie in `rect`, as a list of the same frame.
    SplatList Restrict(const PixelRect& rect);

    // Adds the entries' sums into `tile` (which must cover their pixels): sum[half][c] of each
    // pixel; counts are left alone, since splats are normalised by light paths, not samples.
    void AddTo(TileSums& tile) const;

  private:
    // Makes room for `more` entries without the vector's own doubling (see the file comment).
    void MakeRoom(size_t more);

    int width_ = 0, height_ = 0;
    std::vector<SplatEntry> entries_;
    size_t coalesced_size_ = 0;  // entries_[0, coalesced_size_) are sorted and distinct
};

}  // namespace lf
