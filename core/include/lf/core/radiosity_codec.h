// Radiosity vectors and the results of the farm's patch-group sweep tasks as bytes: the solution
// so far travels from the server to workers as a blob, and each task's rows come back in a
// CompleteTask message. Floats and doubles are copied bit for bit, so a solve split over the
// farm has the bits of one solved in a single process.
//
// Layouts, little-endian:
//   radiosity: "LFRB", u32 version (1), u32 n, then n x (f32 r, g, b)
//   sweep result: "LFSW", u32 version (1), i32 sweep, chunk, sides, side_begin, side_count,
//     group_count, then group_count x (f64 change, f64 power), side_count x (f32 r, g, b) of the
//     input, side_count x (f32 r, g, b) of the output
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/rgb.h"

namespace lf {

std::string EncodeRadiosity(std::span<const Rgb> radiosity);
// InvalidArgument, saying what is wrong, for anything that is not a whole encoding.
absl::StatusOr<std::vector<Rgb>> DecodeRadiosity(std::string_view bytes);

// One patch-group task of a Jacobi sweep: the new radiosity of a run of sides, and per patch
// group of the run the two sums the residual needs (power norm, see radiosity_solver.h).
struct SweepChunkResult {
    int32_t sweep = 0, chunk = 0;
    int32_t sides = 0;                  // unknowns of the whole system
    int32_t side_begin = 0;             // the run: [side_begin, side_begin + input.size())
    std::vector<double> change, power;  // per group: ||output - input||, ||input||
    std::vector<Rgb> input, output;
};

std::string EncodeSweepResult(const SweepChunkResult& result);
// A task's results, one a chunk, back to back.
std::string EncodeSweepResults(std::span<const SweepChunkResult> results);
// At least one result and at most `max_results` (a task holds at most that many chunks: memory
// stays a few times the bytes); InvalidArgument for anything malformed, including a run outside
// [0, sides).
absl::StatusOr<std::vector<SweepChunkResult>> DecodeSweepResults(std::string_view bytes,
                                                                 size_t max_results);

}  // namespace lf
