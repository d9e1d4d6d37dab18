// The cluster tree of hierarchical radiosity (radiosity_hierarchy.h): a binary tree over patch
// sides, built top-down by median splits on centroid position and on normal, so clusters stay
// compact and normal-coherent. Each node covers a contiguous run of the sides in tree order and
// bounds them (box, sphere about the area-weighted centroid, normal cone). The tree depends on
// the sides alone, not on the thread count.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/rgb.h"
#include "lf/core/vec.h"
#include "lf/kernels/form_factors.h"

namespace lf {

// The box, centroid, radius and area in single precision, rounded outward: a node is most of the
// tree's memory, and the tree has two nodes per side. The normal cone and slab stay double: a
// flat cluster's cone must be exactly flat, or coplanar sides would no longer be culled.
struct ClusterNode {
    int32_t begin = 0, end = 0;  // sides in tree order
    int32_t right = -1;          // second child (the first is the next node); -1: a leaf
    Vec3 lo, hi;                 // bounding box of the sides' corners
    Vec3 centroid;               // area-weighted
    float radius = 0;            // bounding sphere about the centroid
    float area = 0;
    Vec3d axis;  // normal cone: every side's normal is within the half-angle of axis
    double cos_half_angle = 1;
    double axis_lo = 0, axis_hi = 0;  // the corners' extent along axis (a slab)

    // Whether the cone is narrower than a half-space (the half-angle below 90 degrees).
    bool narrow() const { return cos_half_angle > 0; }
    double sin_half_angle() const {
        const double c = cos_half_angle;
        return std::sqrt(std::max(0.0, 1 - c * c));
    }
    bool leaf() const { return right < 0; }
    int32_t size() const { return end - begin; }
    // The subtree's nodes are [this node, this node + nodes()) in preorder.
    int32_t nodes() const { return 2 * size() - 1; }
};

class ClusterTree {
  public:
    ClusterTree() = default;
    // Cancelled soon after `cancel` is set. Runs in the caller's TBB arena.
    static absl::StatusOr<ClusterTree> Build(std::span<const SideGeometry> sides,
                                             const std::atomic<bool>* cancel = nullptr);

    const std::vector<ClusterNode>& nodes() const { return nodes_; }  // preorder; 0: the root
    const std::vector<int32_t>& order() const { return order_; }      // tree position -> mesh side
    // Values per side in tree order, in mesh order.
    std::vector<Rgb> ToMeshOrder(std::span<const Rgb> tree_order) const;
    // The roots of the maximal subtrees with at most `max_sides` sides, in tree order: they
    // cover every side once.
    std::vector<int32_t> Cut(int32_t max_sides) const;

  private:
    std::vector<ClusterNode> nodes_;
    std::vector<int32_t> order_;
};

}  // namespace lf
