#include "lf/kernels/cluster_tree.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lf/core/cancel.h"

namespace lf {

namespace {

// Below this many sides a subtree is built on one thread.
constexpr int32_t kParallelSides = 4096;

class Builder {
  public:
    Builder(std::span<const SideGeometry> sides, std::vector<ClusterNode>& nodes,
            std::vector<int32_t>& order, const std::atomic<bool>* cancel)
        : sides_(sides), nodes_(nodes), order_(order), cancel_(cancel) {}

    // Node `index` over tree positions [begin, end); its subtree fills nodes [index, index +
    // 2 (end - begin) - 1), so the node numbers do not depend on which thread builds what.
    void Build(int32_t index, int32_t begin, int32_t end) {
        if (end - begin > 1024 && CancelRequested(cancel_)) return;
        ClusterNode& node = nodes_[size_t(index)];
        Bound(node, begin, end);
        if (end - begin == 1) return;
        const int32_t mid = begin + (end - begin) / 2;
        Split(node, begin, mid, end);
        node.right = index + 2 * (mid - begin);
        if (end - begin < kParallelSides) {
            Build(index + 1, begin, mid);
            Build(node.right, mid, end);
        } else {
            tbb::parallel_invoke([&] { Build(index + 1, begin, mid); },
                                 [&] { Build(node.right, mid, end); });
        }
    }

  private:
    void Bound(ClusterNode& node, int32_t begin, int32_t end) const {
        node.begin = begin;
        node.end = end;
        Vec3d lo(1e300, 1e300, 1e300), hi = -lo, weighted, normals;
        double area = 0;
        for (int32_t t = begin; t < end; ++t) {
            const SideGeometry& s = sides_[size_t(order_[size_t(t)])];
            const double a = Length(Cross(s.p[1] - s.p[0], s.p[2] - s.p[0])) / 2;
            for (const Vec3d& q : s.p) {
                lo = Min(lo, q);
                hi = Max(hi, q);
            }
            area += a;
            weighted += s.c * a;
            normals += s.n * a;
        }
        const Vec3d centroid = area > 0 ? weighted / area : (lo + hi) * 0.5;
        const double length = Length(normals);
        const bool has_axis = length > 1e-9 * area;
        node.axis = has_axis ? normals / length : Vec3d(0, 0, 1);
        node.centroid = Vec3(centroid);
        // The radius is measured from the stored (rounded) centroid.
        const Vec3d c(node.centroid), n = node.axis;
        double cosine = has_axis ? 1.0 : -1.0, radius = 0;
        double axis_lo = 1e300, axis_hi = -1e300;
        for (int32_t t = begin; t < end; ++t) {
            const SideGeometry& s = sides_[size_t(order_[size_t(t)])];
            cosine = std::min(cosine, Dot(n, s.n));
            for (const Vec3d& q : s.p) {
                radius = std::max(radius, Length(q - c));
                axis_lo = std::min(axis_lo, Dot(n, q));
                axis_hi = std::max(axis_hi, Dot(n, q));
            }
        }
        for (int k = 0; k < 3; ++k) {
            node.lo[k] = Down(lo[k]);
            node.hi[k] = Up(hi[k]);
        }
        node.area = float(area);
        node.radius = Up(radius);
        node.cos_half_angle = std::clamp(cosine, -1.0, 1.0);
        node.axis_lo = axis_lo;
        node.axis_hi = axis_hi;
    }

    // The float nearest x on the side away from the node, so bounds stay bounds.
    static float Up(double x) {
        const float f = float(x);
        return double(f) >= x ? f : std::nextafter(f, INFINITY);
    }
    static float Down(double x) {
        const float f = float(x);
        return double(f) <= x ? f : std::nextafter(f, -INFINITY);
    }

    // The median split along the longest of six axes: the centroid's coordinates in units of
    // the node's longest box edge, and the normal's (extent up to 2), so a node whose normals
    // spread more than about 60 degrees splits by orientation first.
    void Split(const ClusterNode& node, int32_t begin, int32_t mid, int32_t end) const {
        const Vec3d extent = Vec3d(node.hi) - Vec3d(node.lo);
        const double longest = std::max({extent.x, extent.y, extent.z, 1e-300});
        Vec3d n_lo(2, 2, 2), n_hi(-2, -2, -2);
        for (int32_t t = begin; t < end; ++t) {
            const Vec3d& n = sides_[size_t(order_[size_t(t)])].n;
            n_lo = Min(n_lo, n);
            n_hi = Max(n_hi, n);
        }
        int axis = 0;
        double best = -1;
        for (int k = 0; k < 6; ++k) {
            const double e = k < 3 ? extent[k] / longest : n_hi[k - 3] - n_lo[k - 3];
            if (e > best) {
                best = e;
                axis = k;
            }
        }
        auto key = [&](int32_t side) {
            const SideGeometry& s = sides_[size_t(side)];
            return axis < 3 ? s.c[axis] : s.n[axis - 3];
        };
        // Ties broken by side index: the split is a function of the sides alone.
        std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                         [&](int32_t a, int32_t b) {
                             const double ka = key(a), kb = key(b);
                             return ka < kb || (ka == kb && a < b);
                         });
    }

    std::span<const SideGeometry> sides_;
    std::vector<ClusterNode>& nodes_;
    std::vector<int32_t>& order_;
    const std::atomic<bool>* cancel_;
};

}  // namespace

absl::StatusOr<ClusterTree> ClusterTree::Build(std::span<const SideGeometry> sides,
                                               const std::atomic<bool>* cancel) {
    ClusterTree tree;
    const int32_t n = int32_t(sides.size());
    if (n == 0) return tree;
    tree.order_.resize(size_t(n));
    for (int32_t s = 0; s < n; ++s) tree.order_[size_t(s)] = s;
    tree.nodes_.resize(2 * size_t(n) - 1);
    Builder(sides, tree.nodes_, tree.order_, cancel).Build(0, 0, n);
    if (CancelRequested(cancel)) return absl::CancelledError("radiosity: cluster tree cancelled");
    return tree;
}

std::vector<Rgb> ClusterTree::ToMeshOrder(std::span<const Rgb> tree_order) const {
    std::vector<Rgb> out(tree_order.size());
    for (size_t t = 0; t < tree_order.size() && t < order_.size(); ++t) {
        out[size_t(order_[t])] = tree_order[t];
    }
    return out;
}

std::vector<int32_t> ClusterTree::Cut(int32_t max_sides) const {
    std::vector<int32_t> roots, stack;
    if (!nodes_.empty()) stack.push_back(0);
    while (!stack.empty()) {
        const int32_t i = stack.back();
        stack.pop_back();
        const ClusterNode& node = nodes_[size_t(i)];
        if (node.leaf() || node.size() <= max_sides) {
            roots.push_back(i);
        } else {
            stack.push_back(node.right);
            stack.push_back(i + 1);
        }
    }
    return roots;
}

}  // namespace lf
