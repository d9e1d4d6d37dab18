// SplatList as bytes: how a task's splats travel and are stored. The exact integer sums go on the
// wire, so splats merged from parts made anywhere have the bits of one list made in one piece.
//
// Layout, little-endian: "LFSP", u32 version (1), i32 width, i32 height (the frame), u64 entry
// count, then per entry, sorted by (pixel, half) with no pair twice: u32 pixel (y * width + x),
// u8 half (0 or 1), three i128 sums (R, G, B; low 64 bits first). 53 bytes an entry, so a list
// restricted to one 192x192 tile (at most 2 entries a pixel) encodes into at most 3.9 MB, under
// gRPC's 4 MiB message limit like a tile (lf/job/plan.h kMaxFarmTile).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/core/splat_list.h"

namespace lf {

// Bytes of an encoded list of `entries` entries.
size_t EncodedSplatListSize(uint64_t entries);

// Coalesces `list` first (lf::SplatList::Coalesce), so equal sums give equal bytes.
std::string EncodeSplatList(SplatList& list);

// InvalidArgument, saying what is wrong, for anything that is not a whole encoded list: a bad
// header, a frame of 2^31 pixels or more, a count the bytes cannot hold (checked before anything
// is allocated), a pixel outside the frame, a half other than 0 or 1, entries out of order or
// repeated, an all-zero entry (the encoder never writes one).
absl::StatusOr<SplatList> DecodeSplatList(std::string_view bytes);

}  // namespace lf
