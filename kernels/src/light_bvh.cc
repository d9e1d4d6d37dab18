#include "lf/kernels/light_bvh.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numbers>
#include <string>

#include "absl/status/status.h"

namespace lf {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;
constexpr int kBuckets = 12;
// The trail of a light holds one bit per level: deeper than this, the build halves the lights
// by count so that no leaf lies deeper than 63.
constexpr int kMaxDepth = 62;

float SurfaceArea(const LightBounds& b) {
    const Vec3 d = b.upper - b.lower;
    return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
}

// The cost of a node in the split heuristic (Conty Estevez & Kulla, eq. 2, as in pbrt-v4): power
// times the measure M_omega of its normal cone widened by theta_e, times its box's surface area;
// Kr penalises thin slabs across the longest axis.
float SplitCost(const LightBounds& b, const Vec3& extent, int dim) {
    const float theta_o = std::acos(std::clamp(b.cos_theta_o, -1.0f, 1.0f));
    const float theta_e = std::acos(std::clamp(b.cos_theta_e, -1.0f, 1.0f));
    const float theta_w = std::min(theta_o + theta_e, kPi);
    const float sin_o = std::sqrt(std::max(0.0f, 1 - b.cos_theta_o * b.cos_theta_o));
    const float m_omega =
        2 * kPi * (1 - b.cos_theta_o) + kPi / 2 *
                                            (2 * theta_w * sin_o - std::cos(theta_o - 2 * theta_w) -
                                             2 * theta_o * sin_o + b.cos_theta_o);
    const float kr = MaxComponent(extent) / extent[dim];
    return b.phi * m_omega * kr * SurfaceArea(b);
}

absl::Status Validate(const LightBounds& b, size_t index) {
    const auto error = [&](const char* what) {
        return absl::InvalidArgumentError("light bounds[" + std::to_string(index) + "]: " + what);
    };
    if (!IsFinite(b.lower) || !IsFinite(b.upper)) return error("box is not finite");
    if (b.lower.x > b.upper.x || b.lower.y > b.upper.y || b.lower.z > b.upper.z) {
        return error("box has lower > upper");
    }
    if (!std::isfinite(b.phi) || b.phi < 0) return error("power is negative or not finite");
    if (!IsFinite(b.axis) || std::abs(Length(b.axis) - 1) > 1e-3f) return error("axis not unit");
    if (!(std::abs(b.cos_theta_o) <= 1) || !(std::abs(b.cos_theta_e) <= 1)) {
        return error("cos_theta_o or cos_theta_e outside [-1, 1]");
    }
    return absl::OkStatus();
}

}  // namespace

absl::StatusOr<LightBvh> LightBvh::Build(std::span<const LightBounds> lights) {
    LightBvh bvh;
    bvh.trail_.assign(lights.size(), 0);
    bvh.in_tree_.assign(lights.size(), false);
    std::vector<BuildLight> build;
    for (size_t i = 0; i < lights.size(); ++i) {
        if (absl::Status status = Validate(lights[i], i); !status.ok()) return status;
        if (lights[i].phi > 0) {
            build.push_back({int(i), lights[i], (lights[i].lower + lights[i].upper) * 0.5f});
        }
    }
    if (!build.empty()) {
        bvh.nodes_.reserve(2 * build.size() - 1);
        bvh.BuildNode(build, 0, build.size(), 0, 0);
    }
    return bvh;
}

int LightBvh::BuildNode(std::vector<BuildLight>& lights, size_t begin, size_t end, int depth,
                        uint64_t trail) {
    const int index = int(nodes_.size());
    if (end - begin == 1) {
        const BuildLight& light = lights[begin];
        nodes_.push_back({light.bounds, uint32_t(light.light), true});
        trail_[size_t(light.light)] = trail;
        in_tree_[size_t(light.light)] = true;
        return index;
    }

    LightBounds bounds;
    Vec3 centroid_lower = lights[begin].centroid, centroid_upper = centroid_lower;
    for (size_t i = begin; i < end; ++i) {
        bounds = Union(bounds, lights[i].bounds);
        centroid_lower = Min(centroid_lower, lights[i].centroid);
        centroid_upper = Max(centroid_upper, lights[i].centroid);
    }
    const Vec3 extent = bounds.upper - bounds.lower;
    const Vec3 centroid_extent = centroid_upper - centroid_lower;

    // The split of least cost over kBuckets buckets of centroids per axis.
    float best_cost = INFINITY;
    int best_dim = -1, best_bucket = -1;
    const size_t count = end - begin;
    const bool by_count = depth + std::bit_width(count - 1) >= kMaxDepth;
    const auto bucket_of = [&](const BuildLight& light, int dim) {
        const float t = (light.centroid[dim] - centroid_lower[dim]) / centroid_extent[dim];
        return std::min(int(t * kBuckets), kBuckets - 1);
    };
    for (int dim = 0; dim < 3 && !by_count; ++dim) {
        if (!(centroid_extent[dim] > 0)) continue;
        std::array<LightBounds, kBuckets> buckets;
        for (size_t i = begin; i < end; ++i) {
            LightBounds& b = buckets[size_t(bucket_of(lights[i], dim))];
            b = Union(b, lights[i].bounds);
        }
        for (int split = 0; split < kBuckets - 1; ++split) {
            LightBounds below, above;
            for (int i = 0; i <= split; ++i) below = Union(below, buckets[size_t(i)]);
            for (int i = split + 1; i < kBuckets; ++i) above = Union(above, buckets[size_t(i)]);
            const float cost = SplitCost(below, extent, dim) + SplitCost(above, extent, dim);
            if (cost < best_cost) {
                best_cost = cost;
                best_dim = dim;
                best_bucket = split;
            }
        }
    }

    size_t mid = begin;
    if (best_dim >= 0) {
        mid =
            size_t(std::partition(
                       lights.begin() + ptrdiff_t(begin), lights.begin() + ptrdiff_t(end),
                       [&](const BuildLight& l) { return bucket_of(l, best_dim) <= best_bucket; }) -
                   lights.begin());
    }
    if (mid == begin || mid == end) {
        // No split separates the centroids (or the tree is deep): halve by count along the
        // widest centroid axis.
        const int dim = centroid_extent.x >= centroid_extent.y
                            ? (centroid_extent.x >= centroid_extent.z ? 0 : 2)
                            : (centroid_extent.y >= centroid_extent.z ? 1 : 2);
        mid = begin + count / 2;
        std::nth_element(lights.begin() + ptrdiff_t(begin), lights.begin() + ptrdiff_t(mid),
                         lights.begin() + ptrdiff_t(end),
                         [dim](const BuildLight& a, const BuildLight& b) {
                             return a.centroid[dim] < b.centroid[dim];
                         });
    }

    nodes_.push_back({bounds, 0, false});
    BuildNode(lights, begin, mid, depth + 1, trail);
    const int second = BuildNode(lights, mid, end, depth + 1, trail | (uint64_t(1) << depth));
    nodes_[size_t(index)].child_or_light = uint32_t(second);
    return index;
}

template <typename Choose>
std::optional<LightPick> LightBvh::Descend(const Vec3& p, const Vec3& n, Choose&& choose) const {
    if (nodes_.empty()) return std::nullopt;
    size_t index = 0;
    float pmf = 1;
    while (!nodes_[index].leaf) {
        const Node& node = nodes_[index];
        const std::array<size_t, 2> children = {index + 1, size_t(node.child_or_light)};
        // In double: two importances near the float maximum still have a finite sum.
        const std::array<double, 2> importance = {nodes_[children[0]].bounds.Importance(p, n),
                                                  nodes_[children[1]].bounds.Importance(p, n)};
        const double total = importance[0] + importance[1];
        if (total == 0) return std::nullopt;
        const int child = choose(float(importance[0] / total));
        const float p_child = float(importance[size_t(child)] / total);
        if (p_child == 0) return std::nullopt;
        pmf *= p_child;
        index = children[size_t(child)];
    }
    // Below the root, p_child > 0 already said the leaf's importance is positive. A single light
    // is picked everywhere, with probability 1: where it cannot reach p its own sampling finds
    // nothing, and the importance it would take to tell costs a scene with one lamp (a Cornell
    // box) a few percent of its time.
    return LightPick{int(nodes_[index].child_or_light), pmf};
}

std::optional<LightPick> LightBvh::SampleTree(const Vec3& p, const Vec3& n, float u) const {
    return Descend(p, n, [&u](float p_first) {
        // Reuse u: rescale its position within the chosen interval back to [0, 1).
        if (u < p_first) {
            u = std::min(u / p_first, kOneMinusEpsilon);
            return 0;
        }
        u = std::min((u - p_first) / (1 - p_first), kOneMinusEpsilon);
        return 1;
    });
}

float LightBvh::Pmf(const Vec3& p, const Vec3& n, int light) const {
    if (light < 0 || size_t(light) >= in_tree_.size() || !in_tree_[size_t(light)]) return 0;
    uint64_t trail = trail_[size_t(light)];
    const std::optional<LightPick> pick = Descend(p, n, [&trail](float) {
        const int child = int(trail & 1);
        trail >>= 1;
        return child;
    });
    return pick ? pick->pmf : 0;
}

}  // namespace lf
