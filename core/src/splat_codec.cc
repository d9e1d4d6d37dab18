#include "lf/core/splat_codec.h"

#include <cstring>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/le_bytes.h"

namespace lf {

namespace {

constexpr char kMagic[4] = {'L', 'F', 'S', 'P'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 4 + 4 + 4 + 4 + 8;
constexpr size_t kEntryBytes = 4 + 1 + 3 * 16;
// Pixel indices are u32 and y * width + x must not wrap.
constexpr int64_t kMaxPixels = int64_t(1) << 31;

absl::Status Bad(const std::string& what) {
    return absl::InvalidArgumentError(absl::StrCat("splat list: ", what));
}

}  // namespace

size_t EncodedSplatListSize(uint64_t entries) { return kHeaderBytes + entries * kEntryBytes; }

std::string EncodeSplatList(SplatList& list) {
    const std::vector<SplatEntry>& entries = list.entries();
    std::string out;
    out.reserve(EncodedSplatListSize(entries.size()));
    out.append(kMagic, 4);
    PutU32(out, kVersion);
    PutU32(out, uint32_t(list.width()));
    PutU32(out, uint32_t(list.height()));
    PutU64(out, entries.size());
    for (const SplatEntry& e : entries) {
        PutU32(out, e.pixel);
        out.push_back(char(e.half));
        for (const ExactSum& s : e.rgb) PutSum(out, s);
    }
    return out;
}

absl::StatusOr<SplatList> DecodeSplatList(std::string_view bytes) {
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, 4) != 0) {
        return Bad(absl::StrCat("not an encoded list (", bytes.size(), " bytes, no LFSP header)"));
    }
    LeReader in(bytes.substr(4));
    const uint32_t version = in.U32();
    if (version != kVersion) {
        return Bad(absl::StrCat("version ", version, " is not the supported ", kVersion));
    }
    const int32_t width = int32_t(in.U32()), height = int32_t(in.U32());
    if (width <= 0 || height <= 0 || int64_t(width) * height >= kMaxPixels) {
        return Bad(absl::StrCat("bad frame ", width, "x", height));
    }
    const uint64_t count = in.U64();
    // Checked by division before anything is allocated: a hostile count cannot overflow it.
    const size_t body = bytes.size() - kHeaderBytes;
    if (count > body / kEntryBytes || body != count * kEntryBytes) {
        return Bad(absl::StrCat(bytes.size(), " bytes for ", count, " entries, which take ",
                                count > body / kEntryBytes ? "more" : "fewer", " (", kEntryBytes,
                                " bytes each after a ", kHeaderBytes, "-byte header)"));
    }
    const uint64_t pixels = uint64_t(width) * uint64_t(height);
    std::vector<SplatEntry> entries(count);
    for (uint64_t i = 0; i < count; ++i) {
        SplatEntry& e = entries[i];
        e.pixel = in.U32();
        e.half = in.U8();
        for (ExactSum& s : e.rgb) s = in.Sum();
        if (e.pixel >= pixels || e.half > 1) {
            return Bad(absl::StrCat("entry ", i, ": pixel ", e.pixel, " half ", int(e.half),
                                    " is not in a ", width, "x", height, " frame's halves 0, 1"));
        }
        if (i > 0 && (entries[i - 1].pixel > e.pixel ||
                      (entries[i - 1].pixel == e.pixel && entries[i - 1].half >= e.half))) {
            return Bad(absl::StrCat("entry ", i, " (pixel ", e.pixel, " half ", int(e.half),
                                    ") is not after entry ", i - 1, " (pixel ",
                                    entries[i - 1].pixel, " half ", int(entries[i - 1].half), ")"));
        }
        if (e.rgb[0].fixed() == 0 && e.rgb[1].fixed() == 0 && e.rgb[2].fixed() == 0) {
            return Bad(absl::StrCat("entry ", i, " (pixel ", e.pixel, ") is all zero"));
        }
    }
    return SplatList::FromCoalesced(width, height, std::move(entries));
}

}  // namespace lf
