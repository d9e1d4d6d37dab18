// Radiosity, the finite-element method for diffuse scenes (docs/radiosity.md): mesh the scene
// into patches, compute form factors with Embree visibility, solve B = E + ρ F B, and render
// the solution through the tile renderer like any other RadianceEstimator. A solution can be
// saved and loaded again for another camera, and exported as a coloured PLY mesh.
//
//   auto renderer = PrepareRadiosity(embree_scene, options);  // meshing, form factors, solve
//   RenderImage(camera, **renderer, settings);                 // any camera, any spp
//
// With a target error the mesh is refined where the solution needs it: solve on the coarse
// mesh, split the patches whose estimated error (radiosity_refinement.h) exceeds the target,
// solve again, until none does or the patch budget is spent.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/radiosity_codec.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/form_factors.h"
#include "lf/kernels/radiance.h"
#include "lf/kernels/radiosity_display.h"
#include "lf/kernels/radiosity_hierarchy.h"
#include "lf/kernels/radiosity_solver.h"

namespace lf {

struct RadiosityOptions {
    double patch_size = 0;   // longest patch edge in scene units; 0: from `patches`
    int64_t patches = 4000;  // target patch count
    RadiositySolver solver = RadiositySolver::kGaussSeidel;
    // Hierarchical radiosity with clustering (radiosity_hierarchy.h): links between clusters of
    // patches, refined until each carries at most `link_error` of the scene's power, solved by
    // Jacobi sweeps; false: the flat n^2 form factors and `solver`.
    bool hierarchical = false;
    double link_error = 1e-4;
    double tolerance = 1e-4;  // relative residual
    int max_iterations = 10000;
    RadiosityShading display = RadiosityShading::kSmooth;
    std::string save_solution;  // paths; empty: none
    std::string load_solution;  // reuse a saved solution, meshed as it was (patch_size and
                                // patches are ignored): no form factors, no solve
    std::string export_ply;
    int threads = 0;  // 0: all cores
    // Relative discretisation error to refine the mesh to (EstimateDiscretisationError); 0: no
    // refinement, the `patches` mesh as it is.
    double target_error = 0;
    // Most patches refinement may reach; 0: 16 times the coarse mesh's. Never above
    // kMaxRefinedPatches.
    int64_t max_patches = 0;
    // Set from another thread: meshing, form factors and the solve stop within a fraction of a
    // second and the call returns Cancelled.
    const std::atomic<bool>* cancel = nullptr;
};

// One solve of a refinement.
struct RadiosityRefinementPass {
    int64_t patches = 0;
    int64_t sides = 0;
    double max_error = 0, mean_error = 0;  // estimated (EstimateDiscretisationError)
    int64_t split = 0;                     // cells split after it
    // Its form factors: those of pairs of patches not split since the previous pass are reused.
    double form_factor_seconds = 0;
    int64_t visibility_rays = 0;
    int64_t pairs = 0, reused_pairs = 0;  // pairs of sides evaluated and reused (FormFactorWork)
};

struct RadiosityReport {
    int64_t patches = 0;
    int64_t sides = 0;  // unknowns
    double patch_size = 0;
    bool loaded = false;  // from a saved solution
    int iterations = 0;   // as in SolveResult (for a loaded solution, those of its solve)
    double sweeps = 0;
    double residual = 0;
    double mesh_seconds = 0, form_factor_seconds = 0, solve_seconds = 0;
    size_t form_factor_bytes = 0;
    int64_t nonzero_form_factors = 0;
    int64_t visibility_rays = 0;
    // Hierarchical (options.hierarchical): links between clusters and between single sides
    // (form_factor_seconds is the linking time), their bytes and all of the solver's (cluster
    // tree, per-side data, links); form_factor_bytes and nonzero_form_factors stay 0.
    int64_t cluster_links = 0, side_links = 0;
    double links_per_side = 0;
    size_t link_bytes = 0, solver_bytes = 0;
    // Estimated discretisation error of the returned solution (also without refinement).
    double estimated_error = 0, mean_estimated_error = 0;
    // With a target error: every solve (the times above are their sums), and why it stopped
    // above the target if it did: the patch budget, or patches already at the finest level.
    std::vector<RadiosityRefinementPass> refinement;
    bool budget_reached = false;
    int64_t finest_above_target = 0;
};

class RadiosityRenderer : public RadianceEstimator {
  public:
    // Per side: the radiosity and all the irradiance arriving (RadiosityDisplay).
    RadiosityRenderer(const EmbreeScene& scene, PatchMesh mesh, std::vector<Rgb> radiosity,
                      std::vector<Rgb> irradiance, RadiosityShading shading,
                      const RadiosityReport& report);

    Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const override {
        return display_->Li(ray, sampler, stats);
    }
    const EmbreeScene& geometry() const override { return display_->geometry(); }
    // The solution's irradiance on the side the ray sees (RadiosityDisplay::Irradiance), shaded
    // as the image is; exact for the solution, so it draws no random numbers.
    std::optional<Rgb> Irradiance(const Ray& ray, Sampler&, RenderStats& stats) const override {
        ++stats.rays;
        const std::optional<SurfaceHit> hit = geometry().Intersect(ray);
        if (!hit || hit->mesh < 0) return Rgb(0);
        return display_->Irradiance(hit->mesh, hit->primitive, hit->b1, hit->b2,
                                    Dot(ray.d, hit->n) > 0);
    }
    const RadiosityDisplay& display() const { return *display_; }

    const RadiosityReport& report() const { return report_; }
    const PatchMesh& mesh() const { return *mesh_; }
    std::span<const Rgb> radiosity() const { return radiosity_; }  // per side, W m^-2

  private:
    std::unique_ptr<const PatchMesh> mesh_;  // stable address for the display
    std::vector<Rgb> radiosity_;
    std::unique_ptr<RadiosityDisplay> display_;
    RadiosityReport report_;
};

// What a farm worker holds of a radiosity job solved in sweeps (lf/job/radiosity_solve.h): the
// mesh and system (hierarchical: the cluster tree), built once, and the form-factor rows
// (hierarchical: the links) of each patch-group chunk it is given, computed once, then swept in
// turn against each sweep's state: the irradiance every side gathered in the sweep before (F B,
// the Jacobi iterate IterateJacobi keeps; B = E + ρ H). A chunk's sums are those SolveRadiosity's
// Jacobi solver makes for its groups, so the farm's solution has its bits, whichever worker
// holds which chunks.
class RadiositySweepChunks {
  public:
    // The same checks as PrepareRadiosity; InvalidArgument for chunks < 1 and for a target error
    // (refinement needs whole solves); Cancelled soon after `cancel` is set. No chunk linked.
    static absl::StatusOr<std::unique_ptr<RadiositySweepChunks>> Make(
        const EmbreeScene& scene, const RadiosityOptions& options, int chunks,
        const std::atomic<bool>* cancel = nullptr);

    // Computes chunk `chunk`'s rows or links, once; InvalidArgument outside 0..chunks-1,
    // Cancelled soon after `cancel` is set (the chunk is then not linked). `scene` as made.
    absl::Status Link(const EmbreeScene& scene, int chunk,
                      const std::atomic<bool>* cancel = nullptr);
    bool Linked(int chunk) const;

    int chunks() const { return chunks_; }
    int32_t sides() const { return int32_t(system().emission.size()); }
    // E, ρ and A per unknown. Hierarchical: the unknowns in the cluster tree's order
    // (RadiosityRendererFor maps them back to the mesh's sides).
    const RadiositySystem& system() const { return hierarchy_ ? hierarchy_->system() : system_; }
    // The state sweep 0 starts from: nothing gathered yet (B = E).
    const std::vector<Rgb>& start() const { return start_; }
    // Hierarchical: the pull up the whole tree of B = E + ρ h, which every chunk's sweep reads
    // (pulled once a sweep for all of them); empty for the flat method.
    std::vector<NodeExitance> Pull(std::span<const Rgb> h) const;
    // A linked chunk's part of one sweep from the gathered irradiance `h` (all sides): its
    // sides' new irradiance from B = E + ρ h, with `pulled` = Pull(h). InvalidArgument when h is
    // not one value per side, the pull is of another size, or the chunk is not linked. Runs in
    // the caller's TBB arena.
    absl::StatusOr<SweepChunkResult> Sweep(int chunk, int32_t sweep, std::span<const Rgb> h,
                                           std::span<const NodeExitance> pulled) const;
    absl::StatusOr<SweepChunkResult> Sweep(int chunk, int32_t sweep, std::span<const Rgb> h) const {
        return Sweep(chunk, sweep, h, Pull(h));
    }
    // Hierarchical: a linked chunk's links, their bytes, and its share of the solver's bytes (the
    // tree and per-side data split evenly over the chunks): summed over the chunks, the farm's
    // EXR header says what local mode's does. Zeros for the flat method.
    RadiosityReport LinkReport(int chunk) const;
    // RadiosityRendererFor with this mesh, cluster tree and direct light, not computed again for
    // the display (the same bits). `options` as made. Spends the holder, whose mesh moves into
    // the renderer (held once, not copied), unless the solution is refused.
    absl::StatusOr<std::unique_ptr<RadiosityRenderer>> Renderer(const EmbreeScene& scene,
                                                                const RadiosityOptions& options,
                                                                std::vector<Rgb> gathered) &&;

  private:
    RadiositySweepChunks() = default;
    std::pair<int32_t, int32_t> Groups(int chunk) const;

    int chunks_ = 1;
    PatchMesh mesh_;
    RadiositySystem system_;                         // flat: E, ρ and A in mesh order
    std::map<int, FormFactors> form_factors_;        // flat: each linked chunk's rows only
    std::unique_ptr<RadiosityHierarchy> hierarchy_;  // instead, hierarchical: every chunk's links
    std::vector<Rgb> direct_;                        // the lights' direct irradiance, mesh order
    std::vector<Rgb> start_;
};

// The renderer of a solution solved elsewhere (by the farm's sweeps): the scene meshed as
// `options` say, the final sweep state `gathered` (hierarchical: in the cluster tree's order)
// giving B = E + ρ H and, with the lights' direct irradiance computed again, the irradiance;
// InvalidArgument unless it holds one value per side, and for a target error (the sweeps solve an
// unrefined mesh).
absl::StatusOr<std::unique_ptr<RadiosityRenderer>> RadiosityRendererFor(
    const EmbreeScene& scene, const RadiosityOptions& options, std::vector<Rgb> gathered);

// The system B = E + ρ F B of `mesh`: E the exitance π L_e of emitters' front sides plus the
// lights' direct light reflected, and that direct irradiance. After `cancel` is set the system is
// unusable: callers check it.
RadiositySystem MakeRadiositySystem(const EmbreeScene& scene, const PatchMesh& mesh,
                                    const FormFactors& form_factors,
                                    const std::atomic<bool>* cancel = nullptr);

// Options from plain values, as `render`, `submit` and the farm's workers receive them;
// InvalidArgument naming a bad solver or display name.
absl::StatusOr<RadiosityOptions> MakeRadiosityOptions(int64_t patches, double patch_size,
                                                      std::string_view solver, double tolerance,
                                                      int max_iterations, std::string_view display);

// Fails with InvalidArgument for scenes radiosity cannot represent (spheres, non-lambert
// materials, reflectance >= 1 with emission), for a solution that does not match the scene,
// with ResourceExhausted if the solver does not converge within the iteration limit, and with
// Cancelled soon after options.cancel is set.
absl::StatusOr<std::unique_ptr<RadiosityRenderer>> PrepareRadiosity(
    const EmbreeScene& scene, const RadiosityOptions& options);

}  // namespace lf
