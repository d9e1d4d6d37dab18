#include "lf/job/tile_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>

#include "absl/strings/str_cat.h"
#include "lf/core/aov.h"
#include "lf/job/merge.h"

namespace lf {

namespace {

std::string RectText(const PixelRect& r) {
    return absl::StrCat(r.x0, ",", r.y0, " ", r.width, "x", r.height);
}

class MemoryTileStore : public TileStore {
  public:
    MemoryTileStore(std::vector<PixelRect> tiles, uint32_t aovs)
        : TileStore(std::move(tiles), aovs) {
        for (const PixelRect& r : this->tiles()) sums_.emplace_back(r, aovs);
    }

    absl::StatusOr<TileSums> Get(int tile) const override {
        if (absl::Status s = CheckIndex(tile); !s.ok()) return s;
        std::lock_guard<std::mutex> lock(mutex_);
        return sums_[size_t(tile)];
    }

    absl::Status Put(int tile, const TileSums& sums) override {
        if (absl::Status s = CheckTile(tile, sums); !s.ok()) return s;
        std::lock_guard<std::mutex> lock(mutex_);
        sums_[size_t(tile)] = sums;
        return absl::OkStatus();
    }

  private:
    mutable std::mutex mutex_;
    std::vector<TileSums> sums_;
};

// A pixel's sums on disk: six 128-bit fixed-point sums, then the two half counts, then the
// store's AOVs (the seven sums of albedo, normal and depth and the depth hits when it has any,
// then the illuminance sum when it has that: stores of builds before it keep their layout); no
// padding.
constexpr size_t kPixelBytes = 6 * sizeof(__int128) + 2 * sizeof(uint32_t);
constexpr size_t AovPixelBytes(uint32_t aovs) {
    if (aovs == 0) return 0;
    return 7 * sizeof(__int128) + sizeof(uint32_t) +
           (aovs & kAovIlluminance ? sizeof(__int128) : 0);
}

char* PutSum(const ExactSum& sum, char* out) {
    const __int128 fixed = sum.fixed();
    std::memcpy(out, &fixed, sizeof(fixed));
    return out + sizeof(fixed);
}

const char* GetSum(const char* in, ExactSum* sum) {
    __int128 fixed;
    std::memcpy(&fixed, in, sizeof(fixed));
    *sum = ExactSum::FromFixed(fixed);
    return in + sizeof(fixed);
}

char* EncodePixel(const PixelSums& p, char* out) {
    for (int h = 0; h < 2; ++h) {
        for (int c = 0; c < 3; ++c) out = PutSum(p.sum[h][c], out);
    }
    std::memcpy(out, p.count, sizeof(p.count));
    return out + sizeof(p.count);
}

const char* DecodePixel(const char* in, PixelSums* p) {
    for (int h = 0; h < 2; ++h) {
        for (int c = 0; c < 3; ++c) in = GetSum(in, &p->sum[h][c]);
    }
    std::memcpy(p->count, in, sizeof(p->count));
    return in + sizeof(p->count);
}

void EncodeAovs(uint32_t aovs, const AovSums& a, char* out) {
    for (const ExactSum& s : a.albedo) out = PutSum(s, out);
    for (const ExactSum& s : a.normal) out = PutSum(s, out);
    out = PutSum(a.depth, out);
    std::memcpy(out, &a.depth_hits, sizeof(a.depth_hits));
    if (aovs & kAovIlluminance) PutSum(a.illuminance, out + sizeof(a.depth_hits));
}

void DecodeAovs(uint32_t aovs, const char* in, AovSums* a) {
    for (ExactSum& s : a->albedo) in = GetSum(in, &s);
    for (ExactSum& s : a->normal) in = GetSum(in, &s);
    in = GetSum(in, &a->depth);
    std::memcpy(&a->depth_hits, in, sizeof(a->depth_hits));
    if (aovs & kAovIlluminance) GetSum(in + sizeof(a->depth_hits), &a->illuminance);
}

class FileTileStore : public TileStore {
  public:
    FileTileStore(std::vector<PixelRect> tiles, uint32_t aovs, int fd, std::string name)
        : TileStore(std::move(tiles), aovs),
          pixel_bytes_(kPixelBytes + AovPixelBytes(aovs)),
          fd_(fd),
          name_(std::move(name)) {
        uint64_t offset = 0;
        for (const PixelRect& r : this->tiles()) {
            offsets_.push_back(offset);
            offset += uint64_t(r.Area()) * pixel_bytes_;
        }
        size_ = offset;
    }
    ~FileTileStore() override { ::close(fd_); }

    uint64_t size() const { return size_; }

    absl::StatusOr<TileSums> Get(int tile) const override {
        if (absl::Status s = CheckIndex(tile); !s.ok()) return s;
        TileSums sums(tiles()[size_t(tile)], aovs());
        std::vector<char> bytes(sums.pixels.size() * pixel_bytes_);
        {
            std::lock_guard<std::mutex> lock(mutex_);
            if (absl::Status s = Transfer(tile, bytes.data(), bytes.size(), false); !s.ok()) {
                return s;
            }
        }
        for (size_t i = 0; i < sums.pixels.size(); ++i) {
            const char* aov = DecodePixel(&bytes[i * pixel_bytes_], &sums.pixels[i]);
            if (aovs() != 0) DecodeAovs(aovs(), aov, &sums.aov_pixels[i]);
        }
        return sums;
    }

    absl::Status Put(int tile, const TileSums& sums) override {
        if (absl::Status s = CheckTile(tile, sums); !s.ok()) return s;
        std::vector<char> bytes(sums.pixels.size() * pixel_bytes_);
        for (size_t i = 0; i < sums.pixels.size(); ++i) {
            char* aov = EncodePixel(sums.pixels[i], &bytes[i * pixel_bytes_]);
            if (aovs() != 0) EncodeAovs(aovs(), sums.aov_pixels[i], aov);
        }
        std::lock_guard<std::mutex> lock(mutex_);
        return Transfer(tile, bytes.data(), bytes.size(), true);
    }

  private:
    // Reads or writes all of tile `tile`'s bytes, resuming after short transfers.
    absl::Status Transfer(int tile, char* data, size_t size, bool write) const {
        uint64_t offset = offsets_[size_t(tile)];
        while (size > 0) {
            const ssize_t n = write ? ::pwrite(fd_, data, size, off_t(offset))
                                    : ::pread(fd_, data, size, off_t(offset));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                return absl::UnavailableError(
                    absl::StrCat(name_, ": cannot ", write ? "write" : "read", " tile ", tile, " (",
                                 RectText(tiles()[size_t(tile)]),
                                 "): ", n < 0 ? std::strerror(errno) : "end of file"));
            }
            data += n;
            size -= size_t(n);
            offset += uint64_t(n);
        }
        return absl::OkStatus();
    }

    const size_t pixel_bytes_;
    const int fd_;
    const std::string name_;
    std::vector<uint64_t> offsets_;
    uint64_t size_ = 0;
    mutable std::mutex mutex_;  // a Get never sees half a Put
};

}  // namespace

absl::Status TileStore::CheckIndex(int tile) const {
    if (tile < 0 || size_t(tile) >= tiles_.size()) {
        return absl::InvalidArgumentError(
            absl::StrCat("no tile ", tile, " in a store of ", tiles_.size()));
    }
    return absl::OkStatus();
}

absl::Status TileStore::CheckTile(int tile, const TileSums& sums) const {
    if (absl::Status s = CheckIndex(tile); !s.ok()) return s;
    const PixelRect& r = tiles_[size_t(tile)];
    if (!(sums.rect == r) || sums.pixels.size() != size_t(r.Area())) {
        return absl::InvalidArgumentError(absl::StrCat("tile ", tile, " is ", RectText(r),
                                                       ": sums of ", RectText(sums.rect), " with ",
                                                       sums.pixels.size(), " pixels"));
    }
    if (sums.aovs != aovs_ || sums.aov_pixels.size() != (aovs_ != 0 ? sums.pixels.size() : 0)) {
        return absl::InvalidArgumentError(
            absl::StrCat("tile ", tile, ": sums with AOVs [", AovListName(sums.aovs),
                         "], the store keeps [", AovListName(aovs_), "]"));
    }
    return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<TileStore>> MakeMemoryTileStore(std::vector<PixelRect> tiles,
                                                               uint32_t aovs) {
    return std::make_unique<MemoryTileStore>(std::move(tiles), aovs);
}

absl::StatusOr<std::unique_ptr<TileStore>> MakeFileTileStore(const std::string& dir,
                                                             std::vector<PixelRect> tiles,
                                                             uint32_t aovs) {
    std::string name = dir + "/tiles-XXXXXX";
    const int fd = ::mkstemp(name.data());
    if (fd < 0) {
        return absl::UnavailableError(
            absl::StrCat(dir, ": cannot make a tile file: ", std::strerror(errno)));
    }
    ::unlink(name.c_str());
    auto store = std::make_unique<FileTileStore>(std::move(tiles), aovs, fd, name);
    // Sparse: a tile takes disk space once it is written, and reads as zero sums before.
    if (::ftruncate(fd, off_t(store->size())) != 0) {
        return absl::UnavailableError(absl::StrCat(name, ": cannot size the tile file to ",
                                                   store->size(),
                                                   " bytes: ", std::strerror(errno)));
    }
    return store;
}

absl::StatusOr<Image> RenderImageOf(const TileStore& store, int width, int height) {
    Image image = EmptyRenderImage(width, height, store.aovs());
    for (int t = 0; t < int(store.tiles().size()); ++t) {
        absl::StatusOr<TileSums> sums = store.Get(t);
        if (!sums.ok()) return sums.status();
        image.SetTile(*sums);
    }
    return image;
}

}  // namespace lf
