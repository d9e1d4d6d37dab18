// Where a radiosity mesh is too coarse: an error indicator from the solution itself, and the
// choice of cells to split so the next solve meets a target (docs/radiosity.md#refinement).
//
// Constant patches approximate a radiosity that varies across them; the smooth display's
// linear interpolation of the vertex values follows the variation to first order. Their
// difference at a patch's corners, the gradient times the patch size, estimates the error of
// the constant value there. It is taken relative to |B| plus the scene's mean radiosity, so
// dark regions are judged against the light in the scene rather than chasing 0/0.
//
// A patch is split when its share of the error, the relative error times its area in units
// of a coarse patch's, exceeds the target. Comparing the relative error alone would spend the
// budget on discontinuities (a box's contact with the floor, the ceiling behind the light),
// where the error does not fall with the patch size, while the smooth gradients that make most
// of the image's error stay coarse; weighted by area, a split there pays off like any other
// (measured on the Cornell box, docs/radiosity.md).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "lf/core/patch_mesh.h"
#include "lf/core/rgb.h"

namespace lf {

// A cell is split at most this many times (patches 16 times smaller than the coarse ones): a
// guard for a target so small that discontinuities would be chased down to the arithmetic.
inline constexpr int kFinestRefinementLevel = 4;

struct DiscretisationError {
    // Per patch, the refinement indicator: the relative error e (below) times 4^-level; 0
    // without sides.
    std::vector<double> indicator;
    double max = 0;   // of the indicator
    double mean = 0;  // of e, area-weighted over the patches with sides: the error overall
};

// e per side: max over its corners of Σ_channels |C - B| / (Σ_channels |B| + mean radiosity),
// C the smooth display's corner value (SmoothCorners) and B the side's constant value; per
// patch the larger of its sides'.
DiscretisationError EstimateDiscretisationError(const PatchMesh& mesh,
                                                std::span<const Rgb> radiosity);

struct RefinementStep {
    std::vector<PatchCell> split;  // cells of `mesh` to split, worst first
    int64_t above_target = 0;      // patches whose indicator exceeds the target
    int64_t at_finest = 0;         // of these, patches already at kFinestRefinementLevel
    bool budget_reached = false;   // splitting them all would exceed max_patches
};

// The patches above `target` that can still be split, worst first (ties by patch order, so the
// choice is deterministic), as many as keep the mesh within max_patches (a split adds three).
RefinementStep ChooseRefinement(const PatchMesh& mesh, const DiscretisationError& error,
                                double target, int64_t max_patches);

}  // namespace lf
