#include "lf/kernels/radiosity.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "lf/core/cancel.h"
#include "lf/core/log.h"
#include "lf/core/patch_mesh.h"
#include "lf/kernels/form_factors.h"
#include "lf/kernels/radiosity_refinement.h"
#include "lf/kernels/radiosity_solution.h"
#include "lf/kernels/radiosity_surfaces.h"

namespace lf {

namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The solver refuses this too, by side index; here the user learns which material it is. What
// radiosity cannot model at all is said first, and what it drops is logged.
absl::Status CheckReflectance(const EmbreeScene& embree) {
    const Scene& scene = embree.scene();
    if (absl::Status refused = RadiosityRefusal(scene); !refused.ok()) return refused;
    if (const std::string drops = RadiosityDrops(scene); !drops.empty()) {
        NamedLogger("radiosity")->info("diffuse parts only; dropped: {}", drops);
    }
    if (!scene.HasLights()) return absl::OkStatus();
    // Textured meshes (whose factor is often 1, scaled down by the texels) are left to the
    // solver's check of every side's average.
    const RadiositySurfaces surfaces(embree);
    for (int mesh = 0; mesh < int(scene.meshes.size()); ++mesh) {
        if (surfaces.Varies(mesh)) continue;
        const Material& m = scene.materials[size_t(scene.meshes[size_t(mesh)].material)];
        const Rgb rho = surfaces.UntexturedReflectance(mesh);
        if (rho.MaxComponent() >= 1) {
            return absl::InvalidArgumentError(absl::StrFormat(
                "radiosity: material '%s' has reflectance (%g, %g, %g); with emission in the "
                "scene a reflectance of 1 or more has no finite solution",
                m.name, rho.r, rho.g, rho.b));
        }
    }
    return absl::OkStatus();
}

absl::Status FormFactorsCancelled() {
    return absl::CancelledError("radiosity: form factors cancelled");
}

// The form factors of `mesh`, reusing `previous`'s where it has them; time and counts add up in
// `report`. Cancelled once `cancel` is set.
absl::StatusOr<FormFactors> FormFactorsOf(const EmbreeScene& scene, const PatchMesh& mesh,
                                          const MeshFormFactors& previous,
                                          const std::atomic<bool>* cancel,
                                          RadiosityReport& report) {
    const auto start = std::chrono::steady_clock::now();
    FormFactorOptions options;
    options.previous = previous;
    options.cancel = cancel;
    FormFactors form_factors = ComputeFormFactors(scene, mesh, options);
    if (CancelRequested(cancel)) return FormFactorsCancelled();
    const double seconds = SecondsSince(start);
    const FormFactorWork& work = form_factors.work();
    report.form_factor_seconds += seconds;
    report.form_factor_bytes = form_factors.bytes();
    report.nonzero_form_factors = form_factors.nonzeros();
    report.visibility_rays += work.rays;
    NamedLogger("radiosity")
        ->info("form factors in {:.2f} s: {} non-zero, {:.1f} MiB, {} rays, {} pairs evaluated{}",
               seconds, form_factors.nonzeros(), double(form_factors.bytes()) / (1 << 20),
               work.rays, work.pairs,
               previous.form_factors ? absl::StrCat(", ", work.reused_pairs, " reused")
                                     : std::string());
    return form_factors;
}

// What the display shows: per side the radiosity and all the irradiance arriving.
struct Solution {
    std::vector<Rgb> radiosity, irradiance;
};

// The lights' direct irradiance plus the gathered one, per side.
std::vector<Rgb> AddDirect(std::span<const Rgb> direct, std::vector<Rgb> gathered) {
    for (size_t i = 0; i < gathered.size(); ++i) gathered[i] += direct[i];
    return gathered;
}

void ReportSolve(const SolveResult& solved, double seconds, RadiosityReport& report) {
    report.solve_seconds += seconds;
    report.iterations = solved.iterations;
    report.sweeps = solved.sweeps;
    report.residual = solved.residual;
}

// The solve on one mesh; times and counts add up in `report`.
absl::StatusOr<Solution> Solve(const EmbreeScene& scene, const PatchMesh& mesh,
                               const FormFactors& form_factors, const RadiosityOptions& options,
                               double tolerance, RadiosityReport& report) {
    const auto start = std::chrono::steady_clock::now();
    const RadiositySystem system = MakeRadiositySystem(scene, mesh, form_factors, options.cancel);
    if (CancelRequested(options.cancel)) return FormFactorsCancelled();
    absl::StatusOr<SolveResult> solved =
        SolveRadiosity(system, {options.solver, tolerance, options.max_iterations, options.cancel});
    if (!solved.ok()) return solved.status();
    const double solve_seconds = SecondsSince(start);
    ReportSolve(*solved, solve_seconds, report);
    NamedLogger("radiosity")
        ->info("{}: {} iterations ({:.1f} sweeps), relative residual {:.2g}, {:.2f} s",
               RadiositySolverName(options.solver), solved->iterations, solved->sweeps,
               solved->residual, solve_seconds);
    return Solution{std::move(solved->radiosity),
                    AddDirect(system.direct, std::move(solved->irradiance))};
}

// The cluster tree of `mesh`, nothing linked; with `direct`, the lights' direct irradiance per
// side there too.
absl::StatusOr<std::unique_ptr<RadiosityHierarchy>> BuildHierarchy(
    const EmbreeScene& scene, const PatchMesh& mesh, const RadiosityOptions& options,
    const std::atomic<bool>* cancel, std::vector<Rgb>* direct = nullptr) {
    const FormFactors none;  // the system's E, ρ and A are all the hierarchy reads
    RadiositySystem system = MakeRadiositySystem(scene, mesh, none, cancel);
    if (CancelRequested(cancel)) return FormFactorsCancelled();
    if (direct) *direct = std::move(system.direct);
    return RadiosityHierarchy::Build(scene, mesh, system,
                                     {options.link_error, kHierarchyGroupSize, cancel});
}

// The hierarchical solve on one mesh; times and counts add up in `report`.
absl::StatusOr<Solution> SolveHierarchically(const EmbreeScene& scene, const PatchMesh& mesh,
                                             const RadiosityOptions& options, double tolerance,
                                             RadiosityReport& report) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<Rgb> direct;
    absl::StatusOr<std::unique_ptr<RadiosityHierarchy>> linked =
        BuildHierarchy(scene, mesh, options, options.cancel, &direct);
    if (!linked.ok()) return linked.status();
    if (absl::Status s = (*linked)->Link(scene, mesh, 0, 1, options.cancel); !s.ok()) return s;
    const RadiosityHierarchy& h = **linked;
    const double link_seconds = SecondsSince(start);
    report.form_factor_seconds += link_seconds;
    report.visibility_rays += h.rays();
    report.cluster_links = h.node_links();
    report.side_links = h.leaf_links();
    report.links_per_side =
        double(h.node_links() + h.leaf_links()) / std::max<double>(1, h.sides());
    report.link_bytes = h.link_bytes();
    report.solver_bytes = h.bytes();
    NamedLogger("radiosity")
        ->info(
            "links in {:.2f} s: {} between clusters, {} between sides ({:.1f} per side), "
            "{:.1f} MiB of {:.1f} MiB, {} rays",
            link_seconds, h.node_links(), h.leaf_links(), report.links_per_side,
            double(h.link_bytes()) / (1 << 20), double(h.bytes()) / (1 << 20), h.rays());
    const auto solve_start = std::chrono::steady_clock::now();
    absl::StatusOr<SolveResult> solved = SolveHierarchical(
        h, {RadiositySolver::kJacobi, tolerance, options.max_iterations, options.cancel});
    if (!solved.ok()) return solved.status();
    const double solve_seconds = SecondsSince(solve_start);
    ReportSolve(*solved, solve_seconds, report);
    NamedLogger("radiosity")
        ->info("hierarchical jacobi: {} sweeps, relative residual {:.2g}, {:.2f} s",
               solved->iterations, solved->residual, solve_seconds);
    return Solution{h.tree().ToMeshOrder(solved->radiosity),
                    AddDirect(direct, h.tree().ToMeshOrder(solved->irradiance))};
}

// Solve, split the patches above the target, mesh again, solve again ... until no patch needs
// splitting or the budget is spent. `mesh` is the coarse mesh on entry, the final one on return.
absl::StatusOr<Solution> SolveRefining(const EmbreeScene& scene, const RadiosityOptions& options,
                                       PatchMesh& mesh, RadiosityReport& report) {
    // The solve's error in B is up to its residual / (1 - ρ) (docs/radiosity.md, Solvers): a
    // tenth of the target keeps it below the discretisation error asked for wherever ρ < 0.9,
    // so the indicator measures the mesh, not an unfinished solve.
    const double tolerance = std::min(options.tolerance, options.target_error / 10);
    const int64_t budget =
        std::min(kMaxRefinedPatches, options.max_patches > 0 ? options.max_patches
                                                             : 16 * int64_t(mesh.patches().size()));
    PatchMeshOptions mesh_options{mesh.patch_size(), 0};
    mesh_options.cancel = options.cancel;
    // The previous pass's mesh and form factors, whose unsplit pairs the next pass reuses: at
    // most two passes' form factors are held at once.
    PatchMesh previous_mesh;
    FormFactors previous;
    for (bool first = true;; first = false) {
        const double form_factor_seconds = report.form_factor_seconds;
        const int64_t rays = report.visibility_rays;
        FormFactors form_factors;  // none for the hierarchical solve, which needs no reuse
        absl::StatusOr<Solution> solution;
        if (options.hierarchical) {
            solution = SolveHierarchically(scene, mesh, options, tolerance, report);
        } else {
            absl::StatusOr<FormFactors> computed = FormFactorsOf(
                scene, mesh, first ? MeshFormFactors{} : MeshFormFactors{&previous_mesh, &previous},
                options.cancel, report);
            if (!computed.ok()) return computed.status();
            form_factors = std::move(*computed);
            previous = FormFactors();  // freed before the solve
            solution = Solve(scene, mesh, form_factors, options, tolerance, report);
        }
        if (!solution.ok()) return solution.status();
        const DiscretisationError error = EstimateDiscretisationError(mesh, solution->radiosity);
        const RefinementStep step = ChooseRefinement(mesh, error, options.target_error, budget);
        const FormFactorWork& work = form_factors.work();
        report.refinement.push_back({int64_t(mesh.patches().size()), int64_t(mesh.sides().size()),
                                     error.max, error.mean, int64_t(step.split.size()),
                                     report.form_factor_seconds - form_factor_seconds,
                                     report.visibility_rays - rays, work.pairs, work.reused_pairs});
        report.budget_reached = step.budget_reached;
        report.finest_above_target = step.at_finest;
        NamedLogger("radiosity")
            ->info(
                "refinement pass {}: {} patches, estimated error max {:.3g} mean {:.3g} (target "
                "{:.3g}), {} patches above it, splitting {}{}",
                report.refinement.size(), mesh.patches().size(), error.max, error.mean,
                options.target_error, step.above_target, step.split.size(),
                step.budget_reached ? " (patch budget reached)" : "");
        if (step.split.empty()) return solution;
        mesh_options.split = mesh.split();
        mesh_options.split.insert(mesh_options.split.end(), step.split.begin(), step.split.end());
        const auto start = std::chrono::steady_clock::now();
        absl::StatusOr<PatchMesh> refined = PatchMesh::Build(scene.scene(), mesh_options);
        if (!refined.ok()) return refined.status();
        previous_mesh = std::exchange(mesh, std::move(*refined));
        previous = std::move(form_factors);
        report.mesh_seconds += SecondsSince(start);
    }
}

absl::StatusOr<std::unique_ptr<RadiosityRenderer>> Prepare(const EmbreeScene& scene,
                                                           const RadiosityOptions& options) {
    const Scene& s = scene.scene();
    if (absl::Status status = CheckReflectance(scene); !status.ok()) return status;
    RadiosityReport report;
    PatchMeshOptions mesh_options{options.patch_size, options.patches};
    RadiositySolution loaded;
    if (!options.load_solution.empty()) {
        absl::StatusOr<RadiositySolution> solution = LoadRadiositySolution(options.load_solution);
        if (!solution.ok()) return solution.status();
        loaded = std::move(*solution);
        mesh_options = {loaded.patch_size, 0, loaded.split};
    }
    mesh_options.cancel = options.cancel;

    const auto start = std::chrono::steady_clock::now();
    absl::StatusOr<PatchMesh> mesh = PatchMesh::Build(s, mesh_options);
    if (!mesh.ok()) {
        if (options.load_solution.empty() || absl::IsCancelled(mesh.status())) {
            return mesh.status();
        }
        return absl::InvalidArgumentError(
            absl::StrCat(options.load_solution, ": ", mesh.status().message()));
    }
    report.mesh_seconds = SecondsSince(start);
    NamedLogger("radiosity")
        ->info("{} patches of size {:.3g}, {} unknowns", mesh->patches().size(), mesh->patch_size(),
               mesh->sides().size());

    Solution solution;
    if (!options.load_solution.empty()) {
        if (absl::Status status =
                CheckRadiositySolution(loaded, options.load_solution, s.content_hash, *mesh);
            !status.ok()) {
            return status;
        }
        report.loaded = true;
        report.iterations = loaded.iterations;
        report.residual = loaded.residual;
        solution = {std::move(loaded.radiosity), std::move(loaded.irradiance)};
        NamedLogger("radiosity")->info("loaded the solution from {}", options.load_solution);
    } else {
        absl::StatusOr<Solution> solved;
        if (options.target_error > 0) {
            solved = SolveRefining(scene, options, *mesh, report);
        } else if (options.hierarchical) {
            solved = SolveHierarchically(scene, *mesh, options, options.tolerance, report);
        } else {
            absl::StatusOr<FormFactors> form_factors =
                FormFactorsOf(scene, *mesh, {}, options.cancel, report);
            if (!form_factors.ok()) return form_factors.status();
            solved = Solve(scene, *mesh, *form_factors, options, options.tolerance, report);
        }
        if (!solved.ok()) return solved.status();
        solution = std::move(*solved);
    }
    report.patches = int64_t(mesh->patches().size());
    report.sides = int64_t(mesh->sides().size());
    report.patch_size = mesh->patch_size();
    const DiscretisationError error = EstimateDiscretisationError(*mesh, solution.radiosity);
    report.estimated_error = error.max;
    report.mean_estimated_error = error.mean;

    if (!options.save_solution.empty()) {
        const RadiositySolution saved{s.content_hash,      mesh->patch_size(), report.patches,
                                      report.iterations,   report.residual,    solution.radiosity,
                                      solution.irradiance, mesh->split()};
        if (absl::Status status = SaveRadiositySolution(options.save_solution, saved);
            !status.ok()) {
            return status;
        }
    }
    auto renderer = std::make_unique<RadiosityRenderer>(
        scene, std::move(*mesh), std::move(solution.radiosity), std::move(solution.irradiance),
        options.display, report);
    if (!options.export_ply.empty()) {
        // The display gives the PLY its illuminance.
        if (absl::Status status = WriteRadiosityPly(options.export_ply, renderer->mesh(),
                                                    renderer->radiosity(), renderer->display());
            !status.ok()) {
            return status;
        }
    }
    return renderer;
}

// The farm's sweeps solve one fixed mesh; refinement re-meshes between solves.
absl::Status CheckNoRefinement(const RadiosityOptions& options) {
    if (options.target_error > 0) {
        return absl::InvalidArgumentError(
            "radiosity: a target error refines the mesh between whole solves; it cannot be "
            "solved in sweeps (use PrepareRadiosity)");
    }
    return absl::OkStatus();
}

absl::Status CheckSolutionSize(const std::vector<Rgb>& gathered, const PatchMesh& mesh) {
    if (gathered.size() == mesh.sides().size()) return absl::OkStatus();
    return absl::InvalidArgumentError(
        absl::StrFormat("radiosity: a solution of %d values for a mesh of %d unknowns",
                        gathered.size(), mesh.sides().size()));
}

// The display of a sweep state solved elsewhere: the radiosity B = E + ρ H, the gathered
// irradiance H and the lights' direct irradiance, all in mesh order.
absl::StatusOr<std::unique_ptr<RadiosityRenderer>> RendererOfSolution(
    const EmbreeScene& scene, const RadiosityOptions& options, PatchMesh mesh,
    std::vector<Rgb> radiosity, std::vector<Rgb> gathered, std::span<const Rgb> direct) {
    RadiosityReport report;
    report.patches = int64_t(mesh.patches().size());
    report.sides = int64_t(mesh.sides().size());
    report.patch_size = mesh.patch_size();
    // As PrepareRadiosity reports it, so the farm's EXR header says what local mode's does.
    const DiscretisationError error = EstimateDiscretisationError(mesh, radiosity);
    report.estimated_error = error.max;
    report.mean_estimated_error = error.mean;
    return std::make_unique<RadiosityRenderer>(scene, std::move(mesh), std::move(radiosity),
                                               AddDirect(direct, std::move(gathered)),
                                               options.display, report);
}

}  // namespace

RadiositySystem MakeRadiositySystem(const EmbreeScene& scene, const PatchMesh& mesh,
                                    const FormFactors& form_factors,
                                    const std::atomic<bool>* cancel) {
    const std::vector<Rgb> irradiance = DirectIrradiance(scene, mesh, cancel);
    RadiositySides sides = RadiositySurfaces(scene).Sides(mesh);
    RadiositySystem system;
    system.form_factors = &form_factors;
    for (size_t s = 0; s < mesh.sides().size(); ++s) {
        system.emission.push_back(sides.reflectance[s] * irradiance[s] + sides.exitance[s]);
        system.area.push_back(mesh.patches()[size_t(mesh.sides()[s].patch)].area);
    }
    system.reflectance = std::move(sides.reflectance);
    system.direct = std::move(irradiance);
    return system;
}

absl::StatusOr<std::unique_ptr<RadiositySweepChunks>> RadiositySweepChunks::Make(
    const EmbreeScene& scene, const RadiosityOptions& options, int chunks,
    const std::atomic<bool>* cancel) {
    if (chunks < 1) {
        return absl::InvalidArgumentError(
            absl::StrFormat("radiosity: %d chunks; at least 1", chunks));
    }
    if (absl::Status status = CheckNoRefinement(options); !status.ok()) return status;
    if (absl::Status status = CheckReflectance(scene); !status.ok()) return status;
    PatchMeshOptions mesh_options{options.patch_size, options.patches};
    mesh_options.cancel = cancel;
    absl::StatusOr<PatchMesh> mesh = PatchMesh::Build(scene.scene(), mesh_options);
    if (!mesh.ok()) return mesh.status();
    std::unique_ptr<RadiositySweepChunks> out(new RadiositySweepChunks());
    out->chunks_ = chunks;
    if (options.hierarchical) {
        absl::StatusOr<std::unique_ptr<RadiosityHierarchy>> built =
            BuildHierarchy(scene, *mesh, options, cancel, &out->direct_);
        if (!built.ok()) return built.status();
        out->hierarchy_ = std::move(*built);
    } else {
        const FormFactors none;  // each chunk's rows come with Link
        out->system_ = MakeRadiositySystem(scene, *mesh, none, cancel);
        if (CancelRequested(cancel)) return FormFactorsCancelled();
        out->system_.form_factors = nullptr;
        out->direct_ = std::move(out->system_.direct);  // the display's, not the sweeps'
    }
    out->mesh_ = std::move(*mesh);
    out->start_.resize(size_t(out->sides()));
    return out;
}

absl::Status RadiositySweepChunks::Link(const EmbreeScene& scene, int chunk,
                                        const std::atomic<bool>* cancel) {
    if (chunk < 0 || chunk >= chunks_) {
        return absl::InvalidArgumentError(
            absl::StrFormat("radiosity: chunk %d of %d does not exist", chunk, chunks_));
    }
    if (hierarchy_) return hierarchy_->Link(scene, mesh_, chunk, chunks_, cancel);
    if (form_factors_.contains(chunk)) return absl::OkStatus();
    FormFactorOptions ff_options;
    ff_options.chunk = chunk;
    ff_options.chunks = chunks_;
    ff_options.cancel = cancel;
    FormFactors rows = ComputeFormFactors(scene, mesh_, ff_options);
    if (CancelRequested(cancel)) return FormFactorsCancelled();
    form_factors_.emplace(chunk, std::move(rows));
    return absl::OkStatus();
}

std::pair<int32_t, int32_t> RadiositySweepChunks::Groups(int chunk) const {
    const size_t groups =
        hierarchy_ ? hierarchy_->groups().size() : form_factors_.at(chunk).groups().size();
    return ChunkGroups(int32_t(groups), chunk, chunks_);
}

bool RadiositySweepChunks::Linked(int chunk) const {
    if (chunk < 0 || chunk >= chunks_) return false;
    if (!hierarchy_) return form_factors_.contains(chunk);
    const auto [g0, g1] = Groups(chunk);
    for (int32_t g = g0; g < g1; ++g) {
        if (!hierarchy_->Linked(g)) return false;
    }
    return true;
}

RadiosityReport RadiositySweepChunks::LinkReport(int chunk) const {
    RadiosityReport report;
    if (!hierarchy_ || !Linked(chunk)) return report;
    const auto [g0, g1] = Groups(chunk);
    const LinkFigures f = hierarchy_->Figures(g0, g1);
    const size_t shared = hierarchy_->shared_bytes();
    report.cluster_links = f.node_links;
    report.side_links = f.leaf_links;
    report.link_bytes = f.bytes;
    // Shares that add up to `shared` exactly over the chunks.
    report.solver_bytes = f.bytes + shared * size_t(chunk + 1) / size_t(chunks_) -
                          shared * size_t(chunk) / size_t(chunks_);
    return report;
}

std::vector<NodeExitance> RadiositySweepChunks::Pull(std::span<const Rgb> h) const {
    if (!hierarchy_ || int64_t(h.size()) != sides()) return {};
    return hierarchy_->Pull(RadiosityFromIrradiance(system(), h));
}

absl::StatusOr<SweepChunkResult> RadiositySweepChunks::Sweep(
    int chunk, int32_t sweep, std::span<const Rgb> h, std::span<const NodeExitance> pulled) const {
    if (int64_t(h.size()) != sides()) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "radiosity sweep %d: %d values for %d unknowns", sweep, h.size(), sides()));
    }
    if (hierarchy_ && pulled.size() != hierarchy_->tree().nodes().size()) {
        return absl::InvalidArgumentError(
            absl::StrFormat("radiosity sweep %d: a pull of %d nodes for a tree of %d", sweep,
                            pulled.size(), hierarchy_->tree().nodes().size()));
    }
    if (!Linked(chunk)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "radiosity sweep %d: chunk %d of %d is not linked here", sweep, chunk, chunks_));
    }
    const FormFactors* rows = hierarchy_ ? nullptr : &form_factors_.at(chunk);
    const auto& groups = hierarchy_ ? hierarchy_->groups() : rows->groups();
    const std::vector<Rgb> b = RadiosityFromIrradiance(system(), h);
    const auto [g0, g1] = Groups(chunk);
    SweepChunkResult r;
    r.sweep = sweep;
    r.chunk = chunk;
    r.sides = sides();
    r.side_begin = g0 < g1 ? groups[size_t(g0)].begin : 0;
    const int32_t side_end = g0 < g1 ? groups[size_t(g1 - 1)].end : 0;
    r.input.assign(h.begin() + r.side_begin, h.begin() + side_end);
    r.output.resize(r.input.size());
    r.change.resize(size_t(g1 - g0));
    r.power.resize(size_t(g1 - g0));
    tbb::parallel_for(g0, g1, [&](int32_t g) {
        const PatchGroup& group = groups[size_t(g)];
        const std::span<Rgb> out = std::span<Rgb>(r.output).subspan(
            size_t(group.begin - r.side_begin), size_t(group.size()));
        const GroupSweep sums = hierarchy_ ? hierarchy_->SweepGroup(g, pulled, b, out)
                                           : JacobiGroup(system_, *rows, g, b, out);
        r.change[size_t(g - g0)] = sums.change;
        r.power[size_t(g - g0)] = sums.power;
    });
    return r;
}

absl::StatusOr<std::unique_ptr<RadiosityRenderer>> RadiositySweepChunks::Renderer(
    const EmbreeScene& scene, const RadiosityOptions& options, std::vector<Rgb> gathered) && {
    if (absl::Status status = CheckSolutionSize(gathered, mesh_); !status.ok()) return status;
    // B = E + ρ H side by side as the sweeps had it; the lights' direct light as Make found it.
    std::vector<Rgb> radiosity = RadiosityFromIrradiance(system(), gathered);
    if (hierarchy_) {
        radiosity = hierarchy_->tree().ToMeshOrder(radiosity);
        gathered = hierarchy_->tree().ToMeshOrder(gathered);
    }
    return RendererOfSolution(scene, options, std::move(mesh_), std::move(radiosity),
                              std::move(gathered), direct_);
}

absl::StatusOr<std::unique_ptr<RadiosityRenderer>> RadiosityRendererFor(
    const EmbreeScene& scene, const RadiosityOptions& options, std::vector<Rgb> gathered) {
    if (absl::Status status = CheckNoRefinement(options); !status.ok()) return status;
    PatchMeshOptions mesh_options{options.patch_size, options.patches};
    mesh_options.cancel = options.cancel;
    absl::StatusOr<PatchMesh> mesh = PatchMesh::Build(scene.scene(), mesh_options);
    if (!mesh.ok()) return mesh.status();
    if (absl::Status status = CheckSolutionSize(gathered, *mesh); !status.ok()) return status;
    if (options.hierarchical) {
        absl::StatusOr<ClusterTree> tree =
            ClusterTree::Build(SideGeometries(scene, *mesh), options.cancel);
        if (!tree.ok()) return tree.status();
        gathered = tree->ToMeshOrder(gathered);
    }
    // B = E + ρ H side by side as the sweeps had it, and the lights' direct irradiance again.
    const FormFactors none;
    const RadiositySystem system = MakeRadiositySystem(scene, *mesh, none, options.cancel);
    if (CancelRequested(options.cancel)) return FormFactorsCancelled();
    std::vector<Rgb> radiosity = RadiosityFromIrradiance(system, gathered);
    return RendererOfSolution(scene, options, std::move(*mesh), std::move(radiosity),
                              std::move(gathered), system.direct);
}

RadiosityRenderer::RadiosityRenderer(const EmbreeScene& scene, PatchMesh mesh,
                                     std::vector<Rgb> radiosity, std::vector<Rgb> irradiance,
                                     RadiosityShading shading, const RadiosityReport& report)
    : mesh_(std::make_unique<const PatchMesh>(std::move(mesh))),
      radiosity_(std::move(radiosity)),
      display_(std::make_unique<RadiosityDisplay>(scene, *mesh_, radiosity_, std::move(irradiance),
                                                  shading)),
      report_(report) {}

absl::StatusOr<std::unique_ptr<RadiosityRenderer>> PrepareRadiosity(
    const EmbreeScene& scene, const RadiosityOptions& options) {
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
    absl::StatusOr<std::unique_ptr<RadiosityRenderer>> result;
    arena.execute([&] { result = Prepare(scene, options); });
    return result;
}

absl::StatusOr<RadiosityOptions> MakeRadiosityOptions(int64_t patches, double patch_size,
                                                      std::string_view solver, double tolerance,
                                                      int max_iterations,
                                                      std::string_view display) {
    RadiosityOptions o;
    absl::StatusOr<RadiositySolver> parsed_solver = ParseRadiositySolver(solver);
    if (!parsed_solver.ok()) return parsed_solver.status();
    absl::StatusOr<RadiosityShading> parsed_display = ParseRadiosityShading(display);
    if (!parsed_display.ok()) return parsed_display.status();
    o.patches = patches;
    o.patch_size = patch_size;
    o.solver = *parsed_solver;
    o.tolerance = tolerance;
    o.max_iterations = max_iterations;
    o.display = *parsed_display;
    return o;
}

}  // namespace lf
