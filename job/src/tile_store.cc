#include "lf/job/tile_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>

#include "absl/strings/str_cat.h"
#include "lf/job/merge.h"

namespace lf {

namespace {

std::string RectText(const PixelRect& r) {
    return absl::StrCat(r.x0, ",", r.y0, " ", r.width, "x", r.height);
}

class MemoryTileStore : public TileStore {
  public:
    explicit MemoryTileStore(std::vector<PixelRect> tiles) : TileStore(std::move(tiles)) {
        for (const PixelRect& r : this->tiles()) sums_.emplace_back(r);
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

// A pixel's sums on disk: six 128-bit fixed-point sums, then the two half counts; no padding.
constexpr size_t kPixelBytes = 6 * sizeof(__int128) + 2 * sizeof(uint32_t);

void EncodePixel(const PixelSums& p, char* out) {
    for (int h = 0; h < 2; ++h) {
        for (int c = 0; c < 3; ++c) {
            const __int128 fixed = p.sum[h][c].fixed();
            std::memcpy(out, &fixed, sizeof(fixed));
            out += sizeof(fixed);
        }
    }
    std::memcpy(out, p.count, sizeof(p.count));
}

PixelSums DecodePixel(const char* in) {
    PixelSums p;
    for (int h = 0; h < 2; ++h) {
        for (int c = 0; c < 3; ++c) {
            __int128 fixed;
            std::memcpy(&fixed, in, sizeof(fixed));
            p.sum[h][c] = ExactSum::FromFixed(fixed);
            in += sizeof(fixed);
        }
    }
    std::memcpy(p.count, in, sizeof(p.count));
    return p;
}

class FileTileStore : public TileStore {
  public:
    FileTileStore(std::vector<PixelRect> tiles, int fd, std::string name)
        : TileStore(std::move(tiles)), fd_(fd), name_(std::move(name)) {
        uint64_t offset = 0;
        for (const PixelRect& r : this->tiles()) {
            offsets_.push_back(offset);
            offset += uint64_t(r.Area()) * kPixelBytes;
        }
        size_ = offset;
    }
    ~FileTileStore() override { ::close(fd_); }

    uint64_t size() const { return size_; }

    absl::StatusOr<TileSums> Get(int tile) const override {
        if (absl::Status s = CheckIndex(tile); !s.ok()) return s;
        TileSums sums(tiles()[size_t(tile)]);
        std::vector<char> bytes(sums.pixels.size() * kPixelBytes);
        {
            std::lock_guard<std::mutex> lock(mutex_);
            if (absl::Status s = Transfer(tile, bytes.data(), bytes.size(), false); !s.ok()) {
                return s;
            }
        }
        for (size_t i = 0; i < sums.pixels.size(); ++i) {
            sums.pixels[i] = DecodePixel(&bytes[i * kPixelBytes]);
        }
        return sums;
    }

    absl::Status Put(int tile, const TileSums& sums) override {
        if (absl::Status s = CheckTile(tile, sums); !s.ok()) return s;
        std::vector<char> bytes(sums.pixels.size() * kPixelBytes);
        for (size_t i = 0; i < sums.pixels.size(); ++i) {
            EncodePixel(sums.pixels[i], &bytes[i * kPixelBytes]);
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
    return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<TileStore>> MakeMemoryTileStore(std::vector<PixelRect> tiles) {
    return std::make_unique<MemoryTileStore>(std::move(tiles));
}

absl::StatusOr<std::unique_ptr<TileStore>> MakeFileTileStore(const std::string& dir,
                                                             std::vector<PixelRect> tiles) {
    std::string name = dir + "/tiles-XXXXXX";
    const int fd = ::mkstemp(name.data());
    if (fd < 0) {
        return absl::UnavailableError(
            absl::StrCat(dir, ": cannot make a tile file: ", std::strerror(errno)));
    }
    ::unlink(name.c_str());
    auto store = std::make_unique<FileTileStore>(std::move(tiles), fd, name);
    // Sparse: a tile takes disk space once it is written, and reads as zero sums before.
    if (::ftruncate(fd, off_t(store->size())) != 0) {
        return absl::UnavailableError(absl::StrCat(name, ": cannot size the tile file to ",
                                                   store->size(),
                                                   " bytes: ", std::strerror(errno)));
    }
    return store;
}

absl::StatusOr<Image> RenderImageOf(const TileStore& store, int width, int height) {
    Image image = EmptyRenderImage(width, height);
    for (int t = 0; t < int(store.tiles().size()); ++t) {
        absl::StatusOr<TileSums> sums = store.Get(t);
        if (!sums.ok()) return sums.status();
        image.SetTile(*sums);
    }
    return image;
}

}  // namespace lf
