#include "lf/core/splat_list.h"

#include <algorithm>
#include <cassert>

namespace lf {

namespace {
// The smallest storage a list reserves (256 KiB): sorting tiny lists often would cost more than
// the memory it saves.
constexpr size_t kMinCapacity = 4096;

bool Before(const SplatEntry& a, const SplatEntry& b) {
    return a.pixel != b.pixel ? a.pixel < b.pixel : a.half < b.half;
}
bool AllZero(const SplatEntry& e) {
    return e.rgb[0].fixed() == 0 && e.rgb[1].fixed() == 0 && e.rgb[2].fixed() == 0;
}
}  // namespace

void SplatList::Add(int x, int y, int half, const Rgb& value) {
    assert(x >= 0 && x < width_ && y >= 0 && y < height_ && (half == 0 || half == 1));
    SplatEntry e;
    e.pixel = uint32_t(y) * uint32_t(width_) + uint32_t(x);
    e.half = uint8_t(half);
    for (int c = 0; c < 3; ++c) e.rgb[c].Add(value[c]);
    MakeRoom(1);
    entries_.push_back(e);
}

SplatList& SplatList::operator+=(const SplatList& other) {
    assert(other.width_ == width_ && other.height_ == height_);
    MakeRoom(other.entries_.size());
    entries_.insert(entries_.end(), other.entries_.begin(), other.entries_.end());
    return *this;
}

void SplatList::MakeRoom(size_t more) {
    if (entries_.size() + more <= entries_.capacity()) return;
    // Full: coalescing first means the storage grows only when the distinct entries need it,
    // and then to 1.5 times what they need. Growing when over 2/3 full leaves at least a third
    // of the storage to fill before the next sort, so sorting costs O(log n) per entry in all.
    Coalesce();
    const size_t need = entries_.size() + more;
    if (need > entries_.capacity() * 2 / 3) {
        entries_.reserve(std::max(kMinCapacity, need + need / 2));
    }
}

void SplatList::Coalesce() {
    if (coalesced()) return;
    // Integer sums: the order of the sort (unstable) cannot change the bits.
    std::sort(entries_.begin(), entries_.end(), Before);
    size_t out = 0;
    for (size_t i = 0; i < entries_.size();) {
        SplatEntry sum = entries_[i];
        size_t j = i + 1;
        for (; j < entries_.size() && !Before(sum, entries_[j]); ++j) {
            for (int c = 0; c < 3; ++c) sum.rgb[c] += entries_[j].rgb[c];
        }
        if (!AllZero(sum)) entries_[out++] = sum;
        i = j;
    }
    entries_.resize(out);
    coalesced_size_ = out;
}

SplatList SplatList::FromCoalesced(int width, int height, std::vector<SplatEntry> entries) {
    SplatList list(width, height);
    list.entries_ = std::move(entries);
    list.coalesced_size_ = list.entries_.size();
    return list;
}

SplatList SplatList::Restrict(const PixelRect& rect) {
    Coalesce();
    SplatList part(width_, height_);
    // Rows of the rectangle are contiguous ranges of pixel indices in the sorted list.
    for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
        const uint32_t first = uint32_t(y) * uint32_t(width_) + uint32_t(rect.x0);
        const uint32_t last = first + uint32_t(rect.width);  // exclusive
        auto it =
            std::lower_bound(entries_.begin(), entries_.end(), first,
                             [](const SplatEntry& e, uint32_t pixel) { return e.pixel < pixel; });
        for (; it != entries_.end() && it->pixel < last; ++it) part.entries_.push_back(*it);
    }
    part.coalesced_size_ = part.entries_.size();
    return part;
}

void SplatList::AddTo(TileSums& tile) const {
    for (const SplatEntry& e : entries_) {
        const int x = int(e.pixel % uint32_t(width_)), y = int(e.pixel / uint32_t(width_));
        PixelSums& p = tile.at(x, y);
        for (int c = 0; c < 3; ++c) p.sum[e.half][c] += e.rgb[c];
    }
}

}  // namespace lf
