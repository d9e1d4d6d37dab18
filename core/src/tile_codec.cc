#include "lf/core/tile_codec.h"

#include <cstring>

#include "absl/strings/str_cat.h"
#include "lf/core/aov.h"
#include "lf/core/le_bytes.h"

namespace lf {

namespace {

constexpr char kMagic[4] = {'L', 'F', 'T', 'S'};
// Version 2 added truncated_paths after invalid_samples; version 1 tiles (from workers of an
// older build) still decode, with no truncated paths. Version 3 adds AOVs; tiles without them
// stay version 2, so their bytes are those of builds before AOVs. Illuminance (flag 8) adds one
// sum a pixel after the others in version 3: older decoders refuse its flag.
constexpr uint32_t kVersion = 2;
constexpr uint32_t kAovVersion = 3;
constexpr uint32_t kOldestVersion = 1;
constexpr size_t HeaderBytes(uint32_t version) {
    return 4 + 4 + 4 * 4 + (version == 1 ? 3 : 4) * 8 + (version >= kAovVersion ? 4 : 0);
}
constexpr size_t kPixelBytes = 6 * 16 + 2 * 4;
constexpr size_t AovPixelBytes(uint32_t aovs) {
    return (aovs & kAovAlbedo ? 3 * 16 : 0) + (aovs & kAovNormal ? 3 * 16 : 0) +
           (aovs & kAovDepth ? 16 + 4 : 0) + (aovs & kAovIlluminance ? 16 : 0);
}
// 2^28 pixels is a 16k x 16k tile: far beyond any plan, small enough that size arithmetic
// cannot overflow and a corrupt header cannot make us allocate terabytes.
constexpr int64_t kMaxPixels = int64_t(1) << 28;

size_t EncodedSize(int64_t pixels, uint32_t version, uint32_t aovs) {
    return HeaderBytes(version) + size_t(pixels) * (kPixelBytes + AovPixelBytes(aovs));
}

}  // namespace

size_t EncodedTileSumsSize(int64_t pixels, uint32_t aovs) {
    return EncodedSize(pixels, aovs == 0 ? kVersion : kAovVersion, aovs);
}

std::string EncodeTileSums(const TileSums& tile) {
    std::string out;
    out.reserve(EncodedTileSumsSize(tile.rect.Area(), tile.aovs));
    out.append(kMagic, 4);
    PutU32(out, tile.aovs == 0 ? kVersion : kAovVersion);
    for (int v : {tile.rect.x0, tile.rect.y0, tile.rect.width, tile.rect.height}) {
        PutU32(out, uint32_t(v));
    }
    for (uint64_t v : {tile.stats.samples, tile.stats.rays, tile.stats.invalid_samples,
                       tile.stats.truncated_paths}) {
        PutU64(out, v);
    }
    if (tile.aovs != 0) PutU32(out, tile.aovs);
    for (const PixelSums& p : tile.pixels) {
        for (int h = 0; h < 2; ++h) {
            for (int c = 0; c < 3; ++c) PutSum(out, p.sum[h][c]);
        }
        PutU32(out, p.count[0]);
        PutU32(out, p.count[1]);
    }
    for (const AovSums& a : tile.aov_pixels) {
        if (tile.aovs & kAovAlbedo) {
            for (const ExactSum& s : a.albedo) PutSum(out, s);
        }
        if (tile.aovs & kAovNormal) {
            for (const ExactSum& s : a.normal) PutSum(out, s);
        }
        if (tile.aovs & kAovDepth) {
            PutSum(out, a.depth);
            PutU32(out, a.depth_hits);
        }
        if (tile.aovs & kAovIlluminance) PutSum(out, a.illuminance);
    }
    return out;
}

absl::StatusOr<TileSums> DecodeTileSums(std::string_view bytes) {
    if (bytes.size() < HeaderBytes(kOldestVersion) || std::memcmp(bytes.data(), kMagic, 4) != 0) {
        return absl::InvalidArgumentError(absl::StrCat("tile sums: not an encoded tile (",
                                                       bytes.size(), " bytes, no LFTS header)"));
    }
    LeReader in(bytes.substr(4));
    const uint32_t version = in.U32();
    if (version < kOldestVersion || version > kAovVersion) {
        return absl::InvalidArgumentError(absl::StrCat("tile sums: version ", version,
                                                       " is not one of the supported ",
                                                       kOldestVersion, "..", kAovVersion));
    }
    if (bytes.size() < HeaderBytes(version)) {
        return absl::InvalidArgumentError(
            absl::StrCat("tile sums: ", bytes.size(), " bytes, shorter than a header"));
    }
    PixelRect rect;
    rect.x0 = in.I32();
    rect.y0 = in.I32();
    rect.width = in.I32();
    rect.height = in.I32();
    // 0x0 at 0,0: no pixels, only the stats (a splat task without a camera part, whose rays
    // still count: lf/kernels/splat_renderer.h).
    const bool no_pixels = rect.x0 == 0 && rect.y0 == 0 && rect.width == 0 && rect.height == 0;
    if (!no_pixels && (rect.x0 < 0 || rect.y0 < 0 || rect.width <= 0 || rect.height <= 0 ||
                       rect.Area() > kMaxPixels)) {
        return absl::InvalidArgumentError(absl::StrCat("tile sums: bad rectangle ", rect.x0, ",",
                                                       rect.y0, " ", rect.width, "x", rect.height));
    }
    RenderStats stats;
    stats.samples = in.U64();
    stats.rays = in.U64();
    stats.invalid_samples = in.U64();
    if (version >= 2) stats.truncated_paths = in.U64();
    const uint32_t aovs = version >= kAovVersion ? in.U32() : 0;
    if (version >= kAovVersion && (aovs == 0 || (aovs & ~kKnownAovs) != 0)) {
        return absl::InvalidArgumentError(
            absl::StrCat("tile sums: AOV flags ", aovs,
                         ": expected a non-empty sum of 1 (albedo), 2 (normal), 4 (depth) and 8 "
                         "(illuminance)"));
    }
    if (bytes.size() != EncodedSize(rect.Area(), version, aovs)) {
        return absl::InvalidArgumentError(
            absl::StrCat("tile sums: ", bytes.size(), " bytes for a ", rect.width, "x", rect.height,
                         " tile, which takes ", EncodedSize(rect.Area(), version, aovs)));
    }
    TileSums tile(rect, aovs);
    tile.stats = stats;
    for (PixelSums& p : tile.pixels) {
        for (int h = 0; h < 2; ++h) {
            for (int c = 0; c < 3; ++c) p.sum[h][c] = in.Sum();
        }
        p.count[0] = in.U32();
        p.count[1] = in.U32();
    }
    for (AovSums& a : tile.aov_pixels) {
        if (aovs & kAovAlbedo) {
            for (ExactSum& s : a.albedo) s = in.Sum();
        }
        if (aovs & kAovNormal) {
            for (ExactSum& s : a.normal) s = in.Sum();
        }
        if (aovs & kAovDepth) {
            a.depth = in.Sum();
            a.depth_hits = in.U32();
        }
        if (aovs & kAovIlluminance) a.illuminance = in.Sum();
    }
    return tile;
}

}  // namespace lf
