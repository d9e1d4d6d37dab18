// Choosing one of many lights by its importance at the shading point (Conty Estevez & Kulla 2018,
// pbrt-v4's BVHLightSampler): a binary tree over the lights' bounds, descended from the root by
// picking each child with probability proportional to its LightBounds::Importance at the point.
// Near, bright lights facing the point get most of the samples; lights that cannot reach it
// (behind a one-sided emitter, outside a spot's cone) get none.
//
// Use (next-event estimation; infinite lights are chosen outside it, e.g. with a fixed
// probability, and the BVH gets the rest):
//   std::vector<LightBounds> bounds = ...;  // one per finite light, by light index
//   absl::StatusOr<LightBvh> bvh = LightBvh::Build(bounds);
//   if (auto pick = bvh->Sample(p, n, u)) { light pick->light, probability pick->pmf }
// and for the MIS weight of a BSDF-sampled ray that hit light i from p (normal n):
//   bvh->Pmf(p, n, i), exactly the pmf Sample returns when it picks i there. n is the shading
// normal at p, or zero in a volume; p and n must be the same in both calls.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/vec.h"
#include "lf/kernels/light_bounds.h"

namespace lf {

struct LightPick {
    int light = 0;  // index into the bounds given to Build
    float pmf = 0;  // probability of this pick, > 0
};

class LightBvh {
  public:
    // A tree with no lights: Sample picks nothing, Pmf is 0.
    LightBvh() = default;

    // The tree over `lights`; lights of zero power are left out (never picked). Fails on
    // bounds that are not finite or inverted, a negative power, an axis that is not unit or a
    // cosine outside [-1, 1], naming the light.
    static absl::StatusOr<LightBvh> Build(std::span<const LightBounds> lights);

    bool empty() const { return nodes_.empty(); }
    size_t node_count() const { return nodes_.size(); }

    // A light for u uniform in [0, 1), with its probability; nullopt if no light can reach p
    // (a tree of one light picks it regardless, with probability 1), and also, as in pbrt-v4, when
    // the walk ends in a subtree whose bounds promised light that none of its lights gives (then
    // the Pmfs sum to less than 1; a failed pick contributes zero and the estimate stays unbiased:
    // every light that can reach p has Pmf > 0).
    std::optional<LightPick> Sample(const Vec3& p, const Vec3& n, float u) const {
        // Inline for a tree of one light (a Cornell box's lamp), which Descend would pick anyway:
        // the call is a measurable part of such a scene's light sampling.
        if (nodes_.size() == 1) return LightPick{int(nodes_[0].child_or_light), 1.0f};
        return SampleTree(p, n, u);
    }
    // The probability that Sample(p, n, .) picks `light`; 0 for a light left out or out of range.
    float Pmf(const Vec3& p, const Vec3& n, int light) const;

  private:
    struct Node {
        LightBounds bounds;
        // Leaf: the light. Inner node: the second child; the first is the next node.
        uint32_t child_or_light = 0;
        bool leaf = false;
    };
    struct BuildLight {
        int light;
        LightBounds bounds;
        Vec3 centroid;
    };

    std::optional<LightPick> SampleTree(const Vec3& p, const Vec3& n, float u) const;
    int BuildNode(std::vector<BuildLight>& lights, size_t begin, size_t end, int depth,
                  uint64_t trail);

    // Walks from the root to a leaf, taking at each inner node the child `choose(p_first)`
    // returns (0 or 1) and multiplying the pmf by that child's probability: Sample and Pmf share
    // it so that their pmfs agree to the bit.
    template <typename Choose>
    std::optional<LightPick> Descend(const Vec3& p, const Vec3& n, Choose&& choose) const;

    std::vector<Node> nodes_;  // depth first, the root first
    // Per light given to Build: the children taken from the root to its leaf (bit d: depth d),
    // and whether it is in the tree at all.
    std::vector<uint64_t> trail_;
    std::vector<bool> in_tree_;
};

}  // namespace lf
