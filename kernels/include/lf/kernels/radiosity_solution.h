// A solved radiosity, saved so other cameras can render it without solving again. The file
// names the scene by content hash and the meshing by its patch size and split cells, so a
// solution is never applied to a scene or mesh it was not computed for.
//
// Binary, little-endian: "LFRADSOL", u32 version (3), u32 length + bytes of the scene hash,
// f64 patch size, i64 patch count, i64 side count, i32 iterations, f64 residual, i64 count of
// split cells and six i32 per cell (mesh, triangle, level, i, j, 1 if upward), then three f32
// (R, G, B radiosity, W m^-2) per side in PatchMesh::sides() order, then three f32 (irradiance,
// W m^-2) per side. Versions 1 and 2 held no irradiance, which the radiosity cannot give where
// a reflectance channel is 0: they are refused (FailedPrecondition, solve again).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/rgb.h"

namespace lf {

struct RadiositySolution {
    std::string scene_hash;
    double patch_size = 0;
    int64_t patches = 0;
    int iterations = 0;
    double residual = 0;
    std::vector<Rgb> radiosity;    // per side
    std::vector<Rgb> irradiance;   // per side: all arriving, the lights' direct included
    std::vector<PatchCell> split;  // PatchMeshOptions::split of the mesh
};

absl::Status SaveRadiositySolution(const std::string& path, const RadiositySolution& solution);
absl::StatusOr<RadiositySolution> LoadRadiositySolution(const std::string& path);

// Fails, naming `path`, unless the solution was computed for this scene and this meshing.
absl::Status CheckRadiositySolution(const RadiositySolution& solution, const std::string& path,
                                    const std::string& scene_hash, const PatchMesh& mesh);

}  // namespace lf
