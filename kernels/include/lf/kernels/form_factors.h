// Form factors between patch sides, with visibility from Embree rays.
//
// F_ij = (1/A_i) ∫_i ∫_j cos θ_i cos θ_j V / (π r^2) dA_j dA_i, the fraction of the view of
// side i (cosine-weighted) taken by side j. The inner integral is exact: Lambert's contour
// integral from a point to the polygon of side j, clipped to the point's hemisphere. The outer
// one is a quadrature over side i that refines as side j gets close: 3 points for far pairs,
// up to 192 where patches touch. Relative error: below 5e-4 for separated pairs, 5e-3 for
// touching ones (docs/radiosity.md). F_ij and F_ji are each integrated over their own
// receiver: then the quadrature errors of a row nearly cancel, and rows of a closed box sum to
// 1 within 1e-5, against 2e-4 if F_ji were derived from F_ij by reciprocity. Reciprocity is
// exploited where it pays, in visibility: each pair shoots its rays once (1, 4 or 16 by
// proximity) and its visible fraction scales F_ij and F_ji alike.
//
// Storage is block-sparse: sides are cut into groups of consecutive sides on one surface side,
// and every pair of groups that can see each other keeps a dense float block over the rows and
// columns that hold non-zeros. Time and memory grow as n^2 in the number of sides.
//
// A pair's two entries depend on the pair alone, not on the rest of the mesh: refinement's next
// pass takes those of pairs whose patches were not split from the previous pass's form factors
// (FormFactorOptions::previous) and evaluates only the pairs with a new patch, with the same bits
// as evaluating them all.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "lf/core/patch_mesh.h"
#include "lf/core/rgb.h"
#include "lf/kernels/embree_scene.h"

namespace lf {

// A run of consecutive sides [begin, end): the unit of form-factor storage and solver work.
struct PatchGroup {
    int32_t begin = 0, end = 0;
    int32_t size() const { return end - begin; }
};

struct FormFactorBlock {
    int32_t row_group = 0, col_group = 0;
    // The sides of the two groups that hold non-zeros: F over [row_begin, row_end) x
    // [col_begin, col_end), row-major.
    int32_t row_begin = 0, row_end = 0, col_begin = 0, col_end = 0;
    std::vector<float> values;

    int32_t cols() const { return col_end - col_begin; }
    float at(int32_t row, int32_t col) const {
        return values[size_t(row - row_begin) * size_t(cols()) + size_t(col - col_begin)];
    }
};

// What a computation cost. A pair is an unordered pair of sides; evaluating it casts its rays and
// integrates both of its entries.
struct FormFactorWork {
    int64_t rays = 0;          // visibility rays cast
    int64_t pairs = 0;         // pairs evaluated
    int64_t reused_pairs = 0;  // pairs taken from FormFactorOptions::previous
};

class FormFactors {
  public:
    FormFactors() = default;
    // `evaluated`: groups x groups, row-major (Evaluated).
    FormFactors(int32_t sides, std::vector<PatchGroup> groups, std::vector<FormFactorBlock> blocks,
                std::vector<bool> evaluated, const FormFactorWork& work);

    int32_t size() const { return sides_; }
    const std::vector<PatchGroup>& groups() const { return groups_; }
    const std::vector<FormFactorBlock>& blocks() const { return blocks_; }
    // The blocks in the rows of `group`, by column group.
    std::span<const FormFactorBlock> RowBlocks(int32_t group) const;
    // Indices into blocks() of the blocks in the columns of `group`, by row group.
    std::span<const int32_t> ColumnBlocks(int32_t group) const;
    int32_t GroupOf(int32_t side) const;

    // F_ij, by search: for tests and diagnostics.
    float At(int32_t i, int32_t j) const;
    double RowSum(int32_t i) const;

    // Whether the entries of the rows of `row_group` in the columns of `col_group` were
    // evaluated; those of a pair of groups culled as unable to see each other are 0 without
    // evaluation, and so are those of rows outside a chunk.
    bool Evaluated(int32_t row_group, int32_t col_group) const {
        return evaluated_[size_t(row_group) * groups_.size() + size_t(col_group)];
    }

    int64_t nonzeros() const { return nonzeros_; }
    size_t bytes() const { return bytes_; }  // block values and indices
    const FormFactorWork& work() const { return work_; }

  private:
    int32_t sides_ = 0;
    std::vector<PatchGroup> groups_;
    std::vector<FormFactorBlock> blocks_;  // sorted by (row_group, col_group)
    std::vector<int32_t> row_start_;       // blocks of row group g: [row_start_[g], [g+1])
    std::vector<int32_t> col_start_, col_blocks_;
    std::vector<bool> evaluated_;  // groups x groups, row-major
    int64_t nonzeros_ = 0;
    size_t bytes_ = 0;
    FormFactorWork work_;
};

// Form factors computed for another mesh of the same scene.
struct MeshFormFactors {
    const PatchMesh* mesh = nullptr;
    const FormFactors* form_factors = nullptr;
};

struct FormFactorOptions {
    int32_t group_size = 64;
    // Only the rows of chunk `chunk` of `chunks` (ChunkGroups): the share of one farm task. Its
    // values are bit for bit those of the whole matrix, as every pair is evaluated in the same
    // order either way; rows of other chunks are left out (no blocks).
    int chunk = 0, chunks = 1;
    // Set from another thread: the remaining pairs are skipped (the result is then unusable).
    const std::atomic<bool>* cancel = nullptr;
    // Refinement's previous pass: a pair of sides whose patches are both cells of that mesh too
    // (same cell of a triangle with the same subdivision) takes its entries from there if they
    // were evaluated, instead of being evaluated again. The result is bit for bit that of
    // evaluating every pair (docs/radiosity.md). Both pointers or neither.
    MeshFormFactors previous;
};

// A side in render space (the scene's origin subtracted), as the form factors see it.
struct SideGeometry {
    std::array<Vec3d, 3> p;
    Vec3d n, c;  // side normal, centroid
    double radius = 0;
    SurfacePoint centre;  // where the single ray of a far pair starts or ends
    int32_t patch = 0;
};

std::vector<SideGeometry> SideGeometries(const EmbreeScene& scene, const PatchMesh& mesh);

struct PairFormFactors {
    double ab = 0, ba = 0;
    int rays = 0;
};

// One pair of sides, as ComputeFormFactors evaluates it: the hierarchical solver's leaf-to-leaf
// links (radiosity_hierarchy.h) use it, so their values are the flat method's bits.
class PairEvaluator {
  public:
    PairEvaluator(const EmbreeScene& scene, const PatchMesh& mesh);

    const std::vector<SideGeometry>& sides() const { return sides_; }
    double epsilon() const { return epsilon_; }  // 1e-6 of the scene's diagonal

    // F_ab and F_ba share the visibility rays, which run from a to b; `ab` or `ba` false skips
    // that one's quadrature (a chunk of rows needs only its own), leaving it 0.
    PairFormFactors Evaluate(int32_t ia, int32_t ib, bool ab = true, bool ba = true) const;

  private:
    const EmbreeScene& scene_;
    const PatchMesh& mesh_;
    std::vector<SideGeometry> sides_;
    double epsilon_ = 0;
};

// Chunk `chunk` of `chunks` of `groups` patch groups, a range; the chunks cover every group
// once, in order. They shrink linearly, the first 1.4 times the mean and the last 0.6 times
// (n = 8; weight 3n - 2k for chunk k): the farm leases sweep 0's chunks in order and a chunk's
// cost is not known before its links are made, so ending on the smaller ones evens out the
// workers' finishing times, while a farm of as many workers as chunks, where the largest chunk
// sets the pace of every sweep, loses less than with a steeper taper.
std::pair<int32_t, int32_t> ChunkGroups(int32_t groups, int chunk, int chunks);

// Runs in the caller's TBB arena; the result does not depend on the thread count.
FormFactors ComputeFormFactors(const EmbreeScene& scene, const PatchMesh& mesh,
                               const FormFactorOptions& options = {});

// Lambert's contour integral: the form factor from a differential area at x with unit normal n
// to a planar polygon that lies in the closed hemisphere n·(p - x) >= 0:
// F = 1/(2π) |Σ_k γ_k n·(r_k × r_k+1) / |r_k × r_k+1||, r_k the unit vectors to the vertices and
// γ_k the angle between consecutive ones.
double PointToPolygonFormFactor(const Vec3d& x, const Vec3d& n, std::span<const Vec3d> polygon);

// Direct irradiance (W m^-2) from the scene's lights on every side, averaged over the side's
// quadrature points (at least 12; finer near point and spot lights), with Embree shadow rays:
// point and spot lights (both falloffs) and directional lights one ray per point, a sun disk 16
// directions uniform in its cone per point, an environment (uniform or a map) 64
// cosine-weighted directions per point. The directions are deterministic (consecutive runs of
// the Sobol sequence), so the result does not depend on the thread count.
// Set `cancel` from another thread: the remaining sides are skipped (the result is then
// unusable; the caller checks the flag).
std::vector<Rgb> DirectIrradiance(const EmbreeScene& scene, const PatchMesh& mesh,
                                  const std::atomic<bool>* cancel = nullptr);

}  // namespace lf
