// TileSums as bytes: how partial results of farm tasks travel. The exact integer sums go on the
// wire, not float means, so a tile merged from parts rendered anywhere has the same bits as one
// rendered in a single piece.
//
// Layout, little-endian: "LFTS", u32 version (2), i32 x0 y0 width height, u64 samples rays
// invalid_samples truncated_paths (version 1 has no truncated_paths), then per pixel row-major: for
// half 0 then 1, three i128 sums (R, G, B; low 64 bits first), then u32 count[0], u32 count[1].
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/core/film.h"

namespace lf {

// Bytes of an encoded tile of `pixels` pixels.
size_t EncodedTileSumsSize(int64_t pixels);

std::string EncodeTileSums(const TileSums& tile);

// InvalidArgument, saying what is wrong, for anything that is not a whole encoded tile. Decodes
// version 1 tiles too, with no truncated paths.
absl::StatusOr<TileSums> DecodeTileSums(std::string_view bytes);

}  // namespace lf
