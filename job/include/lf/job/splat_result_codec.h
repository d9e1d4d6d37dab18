// A splat task's result (lf/job/splat_plan.h) as the job store records it, so that a restarted
// coordinator merges it again to the same bits: its camera sums (lf::EncodeTileSums; a 0x0 tile
// carrying only the stats when the task has no camera part) and its splat list
// (lf::EncodeSplatList), in one record.
//
// Layout, little-endian: "LFFR", u32 version (1), u64 byte count of the camera sums, the camera
// sums, then the splat list to the end.
#pragma once

#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "lf/core/film.h"
#include "lf/core/splat_list.h"

namespace lf {

struct SplatResult {
    TileSums camera{PixelRect{}};
    SplatList splats;
};

// Coalesces the splats (equal sums give equal bytes).
std::string EncodeSplatResult(const TileSums& camera, SplatList& splats);

// InvalidArgument, saying which part is wrong, for anything that is not a whole encoded result.
absl::StatusOr<SplatResult> DecodeSplatResult(std::string_view bytes);

}  // namespace lf
