// TileSums as bytes: how partial results of farm tasks travel. The exact integer sums go on the
// wire, not float means, so a tile merged from parts rendered anywhere has the same bits as one
// rendered in a single piece.
//
// Layout, little-endian: "LFTS", u32 version (2, or 3 with AOVs), i32 x0 y0 width height, u64
// samples rays invalid_samples truncated_paths (version 1 has no truncated_paths), version 3
// only: u32 AOV flags (lf/core/aov.h, not 0); then per pixel row-major: for half 0 then 1, three
// i128 sums (R, G, B; low 64 bits first), then u32 count[0], u32 count[1]; version 3 then adds
// per pixel the AOVs the flags name, in flag order: albedo three i128, normal three i128, depth
// one i128 and u32 depth_hits. A tile without AOVs is version 2, byte for byte as before AOVs.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/core/film.h"

namespace lf {

// Bytes of an encoded tile of `pixels` pixels carrying AOVs `aovs`.
size_t EncodedTileSumsSize(int64_t pixels, uint32_t aovs = 0);

std::string EncodeTileSums(const TileSums& tile);

// InvalidArgument, saying what is wrong, for anything that is not a whole encoded tile (unknown
// AOV flags included). Decodes version 1 tiles too, with no truncated paths. A 0x0 rectangle at
// 0,0 is a tile of no pixels carrying only its stats (a splat task with no camera part).
absl::StatusOr<TileSums> DecodeTileSums(std::string_view bytes);

}  // namespace lf
