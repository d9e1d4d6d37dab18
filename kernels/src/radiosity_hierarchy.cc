#include "lf/kernels/radiosity_hierarchy.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_format.h"
#include "lf/core/cancel.h"

namespace lf {

namespace {

constexpr double kPi = std::numbers::pi;
// Visibility rays of a link between clusters.
constexpr int kClusterRays = 4;
// A link between two clusters joins nodes this many times the sum of their radii apart, at
// least: closer, the irradiance at the receiver's centroid is not its mean (a cluster under the
// light would get the brightest value everywhere). A side is small enough to be linked as soon
// as the bounding spheres are apart.
constexpr double kSeparation = 1.5;
// A partly visible link carries this many times less power than a fully visible one may.
constexpr double kPartialVisibility = 16;

// An upper bound of a·x over the node's corners: the smaller of its box's and that of its slab
// along its axis within its bounding sphere (exact along the axis: coplanar sides of a face that
// is not axis-aligned are culled as coplanar).
double Support(const ClusterNode& node, const Vec3d& a) {
    double box = 0;
    for (int k = 0; k < 3; ++k) box += a[k] * double(a[k] > 0 ? node.hi[k] : node.lo[k]);
    const Vec3d& axis = node.axis;
    const double along = Dot(a, axis);
    const Vec3d across = a - axis * along;
    const double slab = std::max(along * node.axis_lo, along * node.axis_hi) +
                        Dot(across, Vec3d(node.centroid)) + Length(across) * node.radius;
    return std::min(box, slab);
}

// Whether some side of `from` may face some point of `to`: the largest n·(x - y) over normals
// n in from's cone, x in to and y in from, bounded by Support, is above epsilon. Conservative.
bool MayFace(const ClusterNode& from, const ClusterNode& to, double epsilon) {
    if (!from.narrow()) return true;
    const Vec3d& axis = from.axis;
    const double s = Support(to, axis) + Support(from, -axis);
    if (s > epsilon) return true;
    const double reach =
        Length(Vec3d(to.centroid) - Vec3d(from.centroid)) + double(from.radius) + to.radius;
    return s * from.cos_half_angle + reach * from.sin_half_angle() > epsilon;
}

// Whether every normal of the node's cone is within 90 degrees of the unit direction `w`: then
// all its sides face that way, the vector sum of their light is the light sent along w (a side
// facing away would subtract from it), and each side's irradiance from w is n·E.
bool ConeFaces(const ClusterNode& node, const Vec3d& w) {
    // The angle to w plus the half-angle below π/2: cos(angle) > cos(π/2 - half-angle).
    return node.narrow() && Dot(node.axis, w) > node.sin_half_angle();
}

uint64_t Hash(uint64_t x) {
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ULL;
    return x ^ (x >> 33);
}

double Sum(const Rgb& c) { return double(c.r) + c.g + c.b; }

// (row, value) pairs to compressed rows over `rows` rows: a stable counting sort, so each row
// keeps the order its links were made in.
template <typename T>
void Compress(const std::vector<std::pair<int32_t, T>>& links, int32_t rows,
              std::vector<uint32_t>& start, std::vector<T>& values) {
    start.assign(size_t(rows) + 1, 0);
    for (const auto& link : links) ++start[size_t(link.first) + 1];
    for (size_t r = 0; r < size_t(rows); ++r) start[r + 1] += start[r];
    std::vector<uint32_t> next(start.begin(), start.end() - 1);
    values.resize(links.size());
    for (const auto& link : links) values[next[size_t(link.first)]++] = link.second;
}

}  // namespace

// The links of one group at a time; everything it reads is fixed before linking starts.
class RadiosityHierarchy::Linker {
  public:
    Linker(const EmbreeScene& scene, const PairEvaluator& evaluator, const RadiosityHierarchy& h,
           double link_error)
        : scene_(scene), evaluator_(evaluator), h_(h) {
        const auto& nodes = h.tree_.nodes();
        const RadiositySystem& system = h.system_;
        // Brightness estimates: the emission pulled up the tree (area-weighted), plus the
        // ambient term of the whole scene, the light interreflection would add on average.
        // (Scaling it by a node's own reflectance, so black sources draw fewer links, left the
        // Cornell box's small box faces 1.5 % dark at 1e-5.)
        std::vector<Rgb> emitted(nodes.size());
        for (int32_t i = int32_t(nodes.size()) - 1; i >= 0; --i) {
            const ClusterNode& node = nodes[size_t(i)];
            if (node.leaf()) {
                const size_t t = size_t(node.begin);
                emitted[size_t(i)] = system.emission[t] * float(system.area[t]);
            } else {
                emitted[size_t(i)] = emitted[size_t(i) + 1] + emitted[size_t(node.right)];
            }
        }
        double area = 0;
        Rgb reflected;
        for (size_t t = 0; t < system.area.size(); ++t) {
            area += system.area[t];
            reflected += system.reflectance[t] * float(system.area[t]);
        }
        Rgb ambient;
        double power = 0;
        if (!nodes.empty() && area > 0) {
            const Rgb& total = emitted[0];
            power = Sum(total);
            for (int c = 0; c < 3; ++c) {
                const double mean_rho = std::min(double(reflected[c]) / area, 0.999);
                ambient[c] = float(total[c] / area * mean_rho / (1 - mean_rho));
            }
        }
        brightness_.resize(nodes.size());
        for (size_t i = 0; i < nodes.size(); ++i) {
            const double a = std::max(double(nodes[i].area), 1e-300);
            brightness_[i] = Sum(emitted[i]) / a + Sum(ambient);
        }
        threshold_ = link_error * power;
    }

    // Refines the link (group root <- tree root) into the group's links.
    GroupLinks Link(int32_t root, const std::atomic<bool>* cancel, int64_t& rays) const {
        const auto& nodes = h_.tree_.nodes();
        const std::vector<int32_t>& order = h_.tree_.order();
        const ClusterNode& top = nodes[size_t(root)];
        std::vector<std::pair<int32_t, uint32_t>> node_links;  // receiver, source entry
        std::vector<std::pair<int32_t, LeafSource>> leaf_links;
        // A pair, and whether rays already reached its source from its receiver before their
        // cones faced: then they are not tried again until the cones face.
        struct Pair {
            int32_t p, q;
            bool seen;
        };
        std::vector<Pair> stack = {{root, 0, false}};
        int64_t steps = 0;
        while (!stack.empty()) {
            if (++steps % 4096 == 0 && CancelRequested(cancel)) return {};
            const auto [p, q, seen] = stack.back();
            stack.pop_back();
            const ClusterNode &rp = nodes[size_t(p)], &sq = nodes[size_t(q)];
            if (p == q && rp.leaf()) continue;
            if (!MayFace(rp, sq, evaluator_.epsilon()) || !MayFace(sq, rp, evaluator_.epsilon())) {
                continue;
            }
            if (rp.leaf() && sq.leaf()) {
                // As the flat method evaluates the pair: from the lower mesh side, rays and all.
                const int32_t a = order[size_t(rp.begin)], b = order[size_t(sq.begin)];
                const PairFormFactors f =
                    evaluator_.Evaluate(std::min(a, b), std::max(a, b), (a < b), (a > b));
                rays += f.rays;
                const float value = float(a < b ? f.ab : f.ba);
                if (value > 0) leaf_links.push_back({rp.begin - top.begin, {sq.begin, value}});
                continue;
            }
            const Vec3d between = Vec3d(sq.centroid) - Vec3d(rp.centroid);
            const double distance = Length(between);
            const Vec3d d = between / std::max(distance, 1e-300);
            const bool source_faces = ConeFaces(sq, -d), receiver_faces = ConeFaces(rp, d);
            const double separation = rp.leaf() || sq.leaf() ? 1.0 : kSeparation;
            bool split_seen = false;
            if (distance > separation * (rp.radius + sq.radius)) {
                const double near = distance - rp.radius;
                const double bound = std::min(1.0, sq.radius * sq.radius / (near * near));
                const double power = brightness_[size_t(q)] * rp.area * bound;
                // Partly visible: the visible fraction scales the mean exitance of the whole
                // source, though the hidden part's is not the mean (a floor under a box is dark),
                // and the receiver's hidden sides get the same irradiance as its visible ones;
                // such links must carry kPartialVisibility times less. Rays that all miss end
                // the pair, and are tried before the cones face: another room is dropped whole
                // instead of split down to its walls. Such a pair is held to the same stricter
                // bound, since its rays may have missed a door.
                const bool faces = source_faces && receiver_faces;
                const bool strict = power * kPartialVisibility <= threshold_;
                if (power <= threshold_ && (faces || (strict && !seen))) {
                    // Without facing cones a sampled side may face away from the other node, and
                    // its ray start into what is behind it; yet counting only rays between sides
                    // that face each other took 2.8 times the CPU on the 10^6-triangle office
                    // and left the 10^5 one's agreement with the path tracer as it was
                    // (docs/radiosity.md).
                    const int visible = VisibleRays(p, q, rays);
                    if (visible == 0) continue;
                    split_seen = true;
                    if (faces && (visible == kClusterRays || strict)) {
                        node_links.push_back({p - root, uint32_t(q) << 2 | uint32_t(visible - 1)});
                        continue;
                    }
                }
            }
            // A node whose sides do not all face the other is split first.
            const bool child_seen = seen || split_seen;
            const bool split_source =
                rp.leaf() || (!sq.leaf() && (source_faces == receiver_faces ? sq.radius >= rp.radius
                                                                            : !source_faces));
            if (split_source) {
                stack.push_back({p, sq.right, child_seen});
                stack.push_back({p, q + 1, child_seen});
            } else {
                stack.push_back({rp.right, q, child_seen});
                stack.push_back({p + 1, q, child_seen});
            }
        }
        GroupLinks links;
        Compress(node_links, top.nodes(), links.node_start, links.node_source);
        Compress(leaf_links, top.size(), links.leaf_start, links.leaf);
        return links;
    }

  private:
    // A side of `node` facing `target`, chosen by hashing `key` (any side if none faces it).
    int32_t SampleSide(const ClusterNode& node, const Vec3d& target, uint64_t key) const {
        const auto& sides = evaluator_.sides();
        const std::vector<int32_t>& order = h_.tree_.order();
        int32_t side = 0;
        for (uint64_t attempt = 0; attempt < 4; ++attempt) {
            side = order[size_t(node.begin + int32_t(Hash(key + attempt) % uint64_t(node.size())))];
            const SideGeometry& g = sides[size_t(side)];
            if (Dot(g.n, target - g.c) > 0) break;
        }
        return side;
    }

    // How many of kClusterRays rays between points of p and q arrive.
    int VisibleRays(int32_t p, int32_t q, int64_t& rays) const {
        const auto& nodes = h_.tree_.nodes();
        const ClusterNode &rp = nodes[size_t(p)], &sq = nodes[size_t(q)];
        const auto& sides = evaluator_.sides();
        int visible = 0;
        for (int k = 0; k < kClusterRays; ++k) {
            const uint64_t key = Hash((uint64_t(uint32_t(p)) << 32 | uint32_t(q)) * 4 + k);
            const int32_t a = SampleSide(rp, Vec3d(sq.centroid), key);
            const int32_t b = SampleSide(sq, Vec3d(rp.centroid), Hash(key));
            visible +=
                !scene_.Occluded(SpawnRayTo(sides[size_t(a)].centre, sides[size_t(b)].centre));
        }
        rays += kClusterRays;
        return visible;
    }

    const EmbreeScene& scene_;
    const PairEvaluator& evaluator_;
    const RadiosityHierarchy& h_;
    std::vector<double> brightness_;  // per node: estimated radiosity, channels summed
    double threshold_ = 0;            // the most power a link may carry
};

absl::StatusOr<std::unique_ptr<RadiosityHierarchy>> RadiosityHierarchy::Build(
    const EmbreeScene& scene, const PatchMesh& mesh, const RadiositySystem& system,
    const HierarchyOptions& options) {
    const size_t n = mesh.sides().size();
    if (system.emission.size() != n || system.reflectance.size() != n || system.area.size() != n) {
        return absl::InvalidArgumentError("radiosity: system and mesh sizes differ");
    }
    if (!(options.link_error > 0)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("radiosity: link error %g must be > 0", options.link_error));
    }
    if (n >= (size_t(1) << 29)) {  // a link keeps a node (2n - 1 of them) in 30 bits
        return absl::ResourceExhaustedError(
            absl::StrFormat("radiosity: %d sides are too many for the hierarchy", n));
    }
    if (absl::Status status = CheckRadiosityValues(system); !status.ok()) return status;
    std::unique_ptr<RadiosityHierarchy> h(new RadiosityHierarchy());
    // The sides' geometry serves the tree, then goes (each Link makes it again).
    const std::vector<SideGeometry> sides = SideGeometries(scene, mesh);
    absl::StatusOr<ClusterTree> tree = ClusterTree::Build(sides, options.cancel);
    if (!tree.ok()) return tree.status();
    h->tree_ = std::move(*tree);
    for (int32_t side : h->tree_.order()) h->normals_.push_back(sides[size_t(side)].n);
    for (int32_t side : h->tree_.order()) {
        h->system_.emission.push_back(system.emission[size_t(side)]);
        h->system_.reflectance.push_back(system.reflectance[size_t(side)]);
        h->system_.area.push_back(system.area[size_t(side)]);
    }
    h->group_roots_ = h->tree_.Cut(std::max(1, options.group_size));
    for (int32_t root : h->group_roots_) {
        const ClusterNode& node = h->tree_.nodes()[size_t(root)];
        h->groups_.push_back({node.begin, node.end});
    }
    h->link_error_ = options.link_error;
    h->linked_.assign(h->groups_.size(), false);
    h->links_.resize(h->groups_.size());
    return h;
}

absl::Status RadiosityHierarchy::Link(const EmbreeScene& scene, const PatchMesh& mesh, int chunk,
                                      int chunks, const std::atomic<bool>* cancel) {
    if (chunks < 1 || chunk < 0 || chunk >= chunks) {
        return absl::InvalidArgumentError(
            absl::StrFormat("radiosity: chunk %d of %d does not exist", chunk, chunks));
    }
    if (mesh.sides().size() != size_t(sides())) {
        return absl::InvalidArgumentError("radiosity: linking another mesh than the tree's");
    }
    const auto [g0, g1] = ChunkGroups(int32_t(groups_.size()), chunk, chunks);
    const PairEvaluator evaluator(scene, mesh);
    const Linker linker(scene, evaluator, *this, link_error_);
    std::vector<GroupLinks> made(size_t(g1 - g0));
    std::vector<int64_t> rays(size_t(g1 - g0), 0);
    tbb::parallel_for(g0, g1, [&](int32_t g) {
        if (linked_[size_t(g)] || CancelRequested(cancel)) return;
        made[size_t(g - g0)] = linker.Link(group_roots_[size_t(g)], cancel, rays[size_t(g - g0)]);
    });
    // Nothing of a cancelled chunk is kept: it is linked whole or not at all.
    if (CancelRequested(cancel)) return absl::CancelledError("radiosity: linking cancelled");
    for (int32_t g = g0; g < g1; ++g) {
        if (linked_[size_t(g)]) continue;
        GroupLinks& links = links_[size_t(g)];
        links = std::move(made[size_t(g - g0)]);
        linked_[size_t(g)] = true;
        node_links_ += int64_t(links.node_source.size());
        leaf_links_ += int64_t(links.leaf.size());
        rays_ += rays[size_t(g - g0)];
    }
    return absl::OkStatus();
}

std::vector<NodeExitance> RadiosityHierarchy::Pull(std::span<const Rgb> b) const {
    const auto& nodes = tree_.nodes();
    std::vector<NodeExitance> pulled(nodes.size());
    // Each node sums its two children, whichever thread does it: the same bits.
    auto pull = [&](auto& self, int32_t i) -> void {
        const ClusterNode& node = nodes[size_t(i)];
        NodeExitance& out = pulled[size_t(i)];
        if (node.leaf()) {
            const size_t t = size_t(node.begin);
            const Vec3d an = normals_[t] * system_.area[t];
            for (int c = 0; c < 3; ++c) out[size_t(c)] = an * double(b[t][c]);
            return;
        }
        if (node.size() < 4096) {
            self(self, i + 1);
            self(self, node.right);
        } else {
            tbb::parallel_invoke([&] { self(self, i + 1); }, [&] { self(self, node.right); });
        }
        for (size_t c = 0; c < 3; ++c) {
            out[c] = pulled[size_t(i) + 1][c] + pulled[size_t(node.right)][c];
        }
    };
    if (!nodes.empty()) pull(pull, 0);
    return pulled;
}

GroupSweep RadiosityHierarchy::SweepGroup(int32_t group, std::span<const NodeExitance> pulled,
                                          std::span<const Rgb> b, std::span<Rgb> out) const {
    const int32_t root = group_roots_[size_t(group)];
    const auto& nodes = tree_.nodes();
    const ClusterNode& top = nodes[size_t(root)];
    const GroupLinks& links = links_[size_t(group)];
    // Gather: vector irradiance per node of the group's subtree, scalar per side from leaves.
    std::vector<NodeExitance> irradiance(size_t(top.nodes()));
    for (int32_t i = 0; i < top.nodes(); ++i) {
        const Vec3d receiver(nodes[size_t(root + i)].centroid);
        NodeExitance& e = irradiance[size_t(i)];
        for (uint32_t k = links.node_start[size_t(i)]; k < links.node_start[size_t(i) + 1]; ++k) {
            const uint32_t entry = links.node_source[k];
            const int32_t source = int32_t(entry >> 2);
            // Recomputed every sweep rather than stored: links are most of the memory.
            const Vec3d between = Vec3d(nodes[size_t(source)].centroid) - receiver;
            const double r2 = LengthSquared(between);
            const Vec3d d = between / std::sqrt(r2);
            const double scale = double((entry & 3) + 1) / kClusterRays / (kPi * r2);
            for (size_t c = 0; c < 3; ++c) {
                const double toward = -Dot(d, pulled[size_t(source)][c]);
                if (toward > 0) e[c] += d * (scale * toward);
            }
        }
    }
    std::vector<std::array<double, 3>> h(size_t(top.size()), {0, 0, 0});
    for (int32_t i = 0; i < top.size(); ++i) {
        std::array<double, 3>& acc = h[size_t(i)];
        for (uint32_t k = links.leaf_start[size_t(i)]; k < links.leaf_start[size_t(i) + 1]; ++k) {
            const Rgb& source = b[size_t(links.leaf[k].source)];
            for (size_t c = 0; c < 3; ++c) acc[c] += double(links.leaf[k].f) * source[int(c)];
        }
    }
    // Push: a side receives what every ancestor up to the group root received.
    auto push = [&](auto& self, int32_t i, NodeExitance above) -> void {
        const ClusterNode& node = nodes[size_t(i)];
        for (size_t c = 0; c < 3; ++c) above[c] += irradiance[size_t(i - root)][c];
        if (!node.leaf()) {
            self(self, i + 1, above);
            self(self, node.right, above);
            return;
        }
        const Vec3d& n = normals_[size_t(node.begin)];
        std::array<double, 3>& acc = h[size_t(node.begin - top.begin)];
        for (size_t c = 0; c < 3; ++c) acc[c] += std::max(0.0, Dot(n, above[c]));
    };
    push(push, root, NodeExitance{});
    for (size_t k = 0; k < h.size(); ++k) {
        out[k] = Rgb(float(h[k][0]), float(h[k][1]), float(h[k][2]));
    }
    return SweepSums(system_, top.begin, b, out);
}

GroupSweep RadiosityHierarchy::Sweep(std::span<const Rgb> b, std::span<Rgb> next,
                                     const std::atomic<bool>* cancel) const {
    const std::vector<NodeExitance> pulled = Pull(b);
    std::vector<GroupSweep> parts(groups_.size());
    tbb::parallel_for(int32_t(0), int32_t(groups_.size()), [&](int32_t g) {
        if (!linked_[size_t(g)] || CancelRequested(cancel)) return;
        const PatchGroup& group = groups_[size_t(g)];
        parts[size_t(g)] =
            SweepGroup(g, pulled, b, next.subspan(size_t(group.begin), size_t(group.size())));
    });
    GroupSweep total;
    for (const GroupSweep& p : parts) {
        total.change += p.change;
        total.power += p.power;
    }
    return total;
}

LinkFigures RadiosityHierarchy::Figures(int32_t g0, int32_t g1) const {
    LinkFigures f;
    for (int32_t g = g0; g < g1; ++g) {
        const GroupLinks& l = links_[size_t(g)];
        f.node_links += int64_t(l.node_source.size());
        f.leaf_links += int64_t(l.leaf.size());
        f.bytes += (l.node_start.capacity() + l.node_source.capacity() + l.leaf_start.capacity()) *
                       sizeof(uint32_t) +
                   l.leaf.capacity() * sizeof(LeafSource) + sizeof(GroupLinks);
    }
    return f;
}

size_t RadiosityHierarchy::shared_bytes() const {
    const size_t n = size_t(sides());
    const size_t per_side = sizeof(int32_t) + 2 * sizeof(Rgb) + sizeof(double) + sizeof(Vec3d);
    return tree_.nodes().size() * (sizeof(ClusterNode) + sizeof(NodeExitance)) + n * per_side +
           groups_.size() * (sizeof(PatchGroup) + sizeof(int32_t) + 1);
}

absl::StatusOr<SolveResult> SolveHierarchical(const RadiosityHierarchy& hierarchy,
                                              const SolveOptions& options) {
    return IterateJacobi(
        hierarchy.system(),
        [&](std::span<const Rgb> b, std::span<Rgb> gathered, const std::atomic<bool>* cancel) {
            return hierarchy.Sweep(b, gathered, cancel);
        },
        options);
}

}  // namespace lf
