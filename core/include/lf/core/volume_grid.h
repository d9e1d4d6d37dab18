// Loading a participating medium's grid (lf::VolumeGrid, lf/core/medium.h) from an OpenVDB file.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "lf/core/affine.h"
#include "lf/core/medium.h"

namespace lf {

// The most lattice points a grid may hold: 2^28 floats are 1 GiB. A file whose metadata or
// active bounding box says more is refused before anything that size is allocated.
inline constexpr int64_t kMaxVolumeGridPoints = int64_t(1) << 28;

// Float grid `grid_name` of the .vdb file `bytes` (`file_name` names it in messages and in
// VolumeGrid::name): its active voxel bounding box copied densely, its background, and
// index_to_world its own (affine) transform followed by `medium_transform`. InvalidArgument for
// bytes that are not a .vdb file, a missing grid (the message lists the file's grids), a grid of
// another value type, a frustum or singular transform, more than kMaxVolumeGridPoints lattice
// points, and negative or non-finite values (density, emission and temperature are all >= 0).
// FailedPrecondition when OpenVDB's module, liblf_vdb.so of this build, is not where
// lf/core/vdb_reader.h says; Internal for an error OpenVDB raised outside its reads.
absl::StatusOr<std::shared_ptr<const VolumeGrid>> LoadVolumeGrid(const std::string& bytes,
                                                                 const std::string& file_name,
                                                                 const std::string& grid_name,
                                                                 const Affine& medium_transform);

}  // namespace lf
