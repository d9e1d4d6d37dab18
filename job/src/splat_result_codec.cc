#include "lf/job/splat_result_codec.h"

#include <cstdint>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "lf/core/splat_codec.h"
#include "lf/core/tile_codec.h"

namespace lf {

namespace {

constexpr char kMagic[4] = {'L', 'F', 'F', 'R'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 4 + 4 + 8;

void PutLe(std::string& out, uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) out.push_back(char((v >> (8 * i)) & 0xff));
}

uint64_t GetLe(std::string_view in, size_t at, int bytes) {
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= uint64_t(uint8_t(in[at + size_t(i)])) << (8 * i);
    return v;
}

}  // namespace

std::string EncodeSplatResult(const TileSums& camera, SplatList& splats) {
    const std::string tile = EncodeTileSums(camera);
    std::string out(kMagic, 4);
    PutLe(out, kVersion, 4);
    PutLe(out, tile.size(), 8);
    out += tile;
    out += EncodeSplatList(splats);
    return out;
}

absl::StatusOr<SplatResult> DecodeSplatResult(std::string_view bytes) {
    if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, 4) != 0) {
        return absl::InvalidArgumentError(absl::StrCat("splat result: not an encoded result (",
                                                       bytes.size(), " bytes, no LFFR header)"));
    }
    if (const uint64_t version = GetLe(bytes, 4, 4); version != kVersion) {
        return absl::InvalidArgumentError(
            absl::StrCat("splat result: version ", version, ", expected ", kVersion));
    }
    const uint64_t tile_bytes = GetLe(bytes, 8, 8);
    if (tile_bytes > bytes.size() - kHeaderBytes) {
        return absl::InvalidArgumentError(absl::StrCat("splat result: camera sums of ", tile_bytes,
                                                       " bytes in a record of ", bytes.size()));
    }
    absl::StatusOr<TileSums> camera = DecodeTileSums(bytes.substr(kHeaderBytes, tile_bytes));
    if (!camera.ok()) return camera.status();
    absl::StatusOr<SplatList> splats = DecodeSplatList(bytes.substr(kHeaderBytes + tile_bytes));
    if (!splats.ok()) return splats.status();
    return SplatResult{std::move(*camera), std::move(*splats)};
}

}  // namespace lf
