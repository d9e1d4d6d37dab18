// Hierarchical radiosity with clustering (face clusters, Willmott, Heckbert & Garland 1999, with
// Hanrahan, Salzman & Aupperle's links, 1991), docs/radiosity.md "Hierarchical": time and memory
// about linear in the number of sides, where the flat form factors grow as n^2.
//
// The leaves of a cluster tree (cluster_tree.h) are the mesh's sides. The cut of the tree at
// kHierarchyGroupSize sides makes the groups; each group's root is linked to the tree's root,
// and a link is split (at its node with the larger bounding sphere, never above the group root
// for the receiver) until the power it may carry is below link_error times the scene's emitted
// power. Two leaves are linked by their exact form factor (PairEvaluator: the flat method's
// bits); clusters exchange light as vector irradiance. No link has a receiver above its group,
// so a group's gather and push are independent of every other group: a farm chunk links and
// sweeps its groups alone and the sums are those of the whole solve.
//
// The unknowns are in tree order (ClusterTree::ToMeshOrder maps them to the mesh's sides).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/patch_mesh.h"
#include "lf/kernels/cluster_tree.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/form_factors.h"
#include "lf/kernels/radiosity_solver.h"

namespace lf {

// Sides per group at most: enough to amortise a group's task, few enough for a farm's chunks.
inline constexpr int32_t kHierarchyGroupSize = 256;

struct HierarchyOptions {
    double link_error = 1e-4;  // of the scene's emitted power, per link
    int32_t group_size = kHierarchyGroupSize;
    // Set from another thread: Build and Link return Cancelled soon after.
    const std::atomic<bool>* cancel = nullptr;
};

// The links of some of a hierarchy's groups: their counts and bytes.
struct LinkFigures {
    int64_t node_links = 0, leaf_links = 0;
    size_t bytes = 0;
};

// Per node and channel, Σ B A n over its sides.
using NodeExitance = std::array<Vec3d, 3>;

class RadiosityHierarchy {
  public:
    // The cluster tree and groups of `mesh`, nothing linked yet. `system`: E, ρ and A per side in
    // mesh order (MakeRadiositySystem's). Runs in the caller's TBB arena.
    static absl::StatusOr<std::unique_ptr<RadiosityHierarchy>> Build(
        const EmbreeScene& scene, const PatchMesh& mesh, const RadiositySystem& system,
        const HierarchyOptions& options);
    // Links the groups of chunk `chunk` of `chunks` (ChunkGroups; 0 of 1: all of them) that are
    // not linked yet: a farm worker links each chunk it is given into one hierarchy, whose tree
    // it builds once. `scene` and `mesh` as built. The links do not depend on the thread count.
    absl::Status Link(const EmbreeScene& scene, const PatchMesh& mesh, int chunk, int chunks,
                      const std::atomic<bool>* cancel = nullptr);

    int32_t sides() const { return int32_t(system_.emission.size()); }
    const ClusterTree& tree() const { return tree_; }
    // E, ρ and A in tree order (form_factors is null).
    const RadiositySystem& system() const { return system_; }
    const std::vector<PatchGroup>& groups() const { return groups_; }  // in tree order
    bool Linked(int32_t group) const { return linked_[size_t(group)]; }

    // Every node's exitance from b (tree order): the pull, O(n).
    std::vector<NodeExitance> Pull(std::span<const Rgb> b) const;
    // One group's Jacobi step: out = H(b), the irradiance its sides gather (over its links,
    // pushed down to its sides), and JacobiGroup's sums (SweepSums). `pulled` is Pull(b).
    GroupSweep SweepGroup(int32_t group, std::span<const NodeExitance> pulled,
                          std::span<const Rgb> b, std::span<Rgb> out) const;
    // SweepGroup over every linked group; the sums in group order. Stops early once `cancel`
    // is set (the result is then meaningless).
    GroupSweep Sweep(std::span<const Rgb> b, std::span<Rgb> gathered,
                     const std::atomic<bool>* cancel = nullptr) const;

    int64_t node_links() const { return node_links_; }
    int64_t leaf_links() const { return leaf_links_; }
    int64_t rays() const { return rays_; }  // of every Link so far
    size_t link_bytes() const { return Figures(0, int32_t(groups_.size())).bytes; }
    // The links of groups [g0, g1).
    LinkFigures Figures(int32_t g0, int32_t g1) const;
    size_t shared_bytes() const;  // tree and per-side data: all but the links
    size_t bytes() const { return shared_bytes() + link_bytes(); }

  private:
    // A group's links by receiver, in compressed rows: links are most of the solver's memory.
    // Node i of the group's subtree (root + i) gathers from node_source[node_start[i] ..
    // node_start[i + 1]), each entry a source node << 2 | (visible rays - 1) of kClusterRays (4)
    // (the direction is that of the centroids); side begin + i from leaf[leaf_start[i] ..
    // leaf_start[i + 1]).
    struct LeafSource {
        int32_t source;  // tree position
        float f;         // F_receiver,source
    };
    struct GroupLinks {
        std::vector<uint32_t> node_start, node_source, leaf_start;
        std::vector<LeafSource> leaf;
    };
    class Linker;

    RadiosityHierarchy() = default;

    ClusterTree tree_;
    RadiositySystem system_;
    std::vector<Vec3d> normals_;  // per side, tree order
    std::vector<PatchGroup> groups_;
    std::vector<int32_t> group_roots_;
    double link_error_ = 0;
    std::vector<bool> linked_;       // per group
    std::vector<GroupLinks> links_;  // per group; empty where not linked
    int64_t node_links_ = 0, leaf_links_ = 0, rays_ = 0;
};

// Jacobi sweeps over every group until the relative residual is below the tolerance, as
// SolveRadiosity's Jacobi solver stops; the radiosity and gathered irradiance in tree order.
// ResourceExhausted at the iteration limit, Cancelled soon after options.cancel is set.
absl::StatusOr<SolveResult> SolveHierarchical(const RadiosityHierarchy& hierarchy,
                                              const SolveOptions& options);

}  // namespace lf
