#include "lf/kernels/form_factors.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numbers>

#include "lf/core/cancel.h"
#include "lf/core/light_strategy.h"
#include "lf/core/log.h"
#include "lf/core/sobol.h"
#include "lf/kernels/bsdf_sampling.h"
#include "lf/kernels/environment_emitter.h"
#include "lf/kernels/light_list.h"
#include "lf/kernels/lights.h"

namespace lf {

namespace {

// The contour integral's angles ------------------------------------------------------------

// atan(t) for t in [0, 1], Cephes' rational approximation (relative error ~1e-16): libm's
// atan2 took 40 % of the form-factor time.
double AtanUnit(double t) {
    constexpr double kP[] = {-8.750608600031904122785e-1, -1.615753718733365076637e1,
                             -7.500855792314704667340e1, -1.228866684490136173410e2,
                             -6.485021904942025371773e1};
    constexpr double kQ[] = {2.485846490142306297962e1, 1.650270098316988542046e2,
                             4.328810604912902668951e2, 4.853903996359136964868e2,
                             1.945506571482613964425e2};
    double base = 0;
    if (t > 0.66) {
        base = std::numbers::pi / 4;
        t = (t - 1) / (t + 1);
    }
    const double z = t * t;
    const double p = (((kP[0] * z + kP[1]) * z + kP[2]) * z + kP[3]) * z + kP[4];
    const double q = ((((z + kQ[0]) * z + kQ[1]) * z + kQ[2]) * z + kQ[3]) * z + kQ[4];
    return base + (t + t * z * p / q);
}

// γ / sin γ for the angle γ in [0, π] between two unit vectors, from |a x b|^2 = sin^2 γ and
// a·b = cos γ. Far patches subtend small angles, where the series of atan(t)/t in t = tan γ
// needs no square root and a single division (8 terms: error < 1e-17 for t < 0.1).
double AngleOverSine(double sin2, double cosine) {
    if (cosine > 0 && sin2 < 0.01 * cosine * cosine) {
        const double inv = 1 / cosine, x = -sin2 * inv * inv, x2 = x * x;
        // Σ x^k / (2k + 1) for k < 8 in Estrin's scheme: short dependency chains.
        const double low = (1 + x * (1.0 / 3)) + x2 * (1.0 / 5 + x * (1.0 / 7));
        const double high = (1.0 / 9 + x * (1.0 / 11)) + x2 * (1.0 / 13 + x * (1.0 / 15));
        return (low + x2 * x2 * high) * inv;
    }
    const double sine = std::sqrt(sin2), c = std::abs(cosine);
    double a = sine <= c ? AtanUnit(sine / c) : std::numbers::pi / 2 - AtanUnit(c / sine);
    if (cosine < 0) a = std::numbers::pi - a;
    return a / sine;
}

// Quadrature over a patch ------------------------------------------------------------------

// A node in barycentric weights on the patch's corners, and its weight (weights sum to 1).
struct Node {
    std::array<double, 3> w;
    double weight;
};

using Corners = std::array<std::array<double, 3>, 3>;

// The patch split into 4^level congruent sub-triangles, corners in barycentric weights.
std::vector<Corners> SubTriangles(int level) {
    const int q = 1 << level;
    std::vector<Corners> triangles;
    for (const GridTriangle& cell : SubdivisionCells(q)) {
        Corners c;
        for (size_t k = 0; k < 3; ++k) {
            const double b1 = double(cell[k][0]) / q, b2 = double(cell[k][1]) / q;
            c[k] = {1 - b1 - b2, b1, b2};
        }
        triangles.push_back(c);
    }
    return triangles;
}

// Level l: the degree-2 three-point rule (nodes at barycentrics 2/3, 1/6, 1/6) on each of the
// 4^l sub-triangles.
constexpr int kMaxLevel = 3;

std::vector<Node> QuadratureRule(int level) {
    const std::vector<Corners> triangles = SubTriangles(level);
    const double weight = 1.0 / (3.0 * double(triangles.size()));
    std::vector<Node> nodes;
    for (const Corners& c : triangles) {
        for (size_t r = 0; r < 3; ++r) {
            Node node{{0, 0, 0}, weight};
            for (size_t k = 0; k < 3; ++k) {
                const double lambda = k == r ? 2.0 / 3 : 1.0 / 6;
                for (size_t m = 0; m < 3; ++m) node.w[m] += lambda * c[k][m];
            }
            nodes.push_back(node);
        }
    }
    return nodes;
}

// Visibility rays join centroids of sub-triangles: 1, 4 or 16 per patch.
constexpr int kMaxRayLevel = 2;

std::vector<std::array<double, 3>> RayPoints(int level) {
    std::vector<std::array<double, 3>> points;
    for (const Corners& c : SubTriangles(level)) {
        points.push_back({(c[0][0] + c[1][0] + c[2][0]) / 3, (c[0][1] + c[1][1] + c[2][1]) / 3,
                          (c[0][2] + c[1][2] + c[2][2]) / 3});
    }
    return points;
}

struct Rules {
    std::array<std::vector<Node>, kMaxLevel + 1> quadrature;
    std::array<std::vector<std::array<double, 3>>, kMaxRayLevel + 1> rays;
    Rules() {
        for (int l = 0; l <= kMaxLevel; ++l) quadrature[size_t(l)] = QuadratureRule(l);
        for (int l = 0; l <= kMaxRayLevel; ++l) rays[size_t(l)] = RayPoints(l);
    }
};

const Rules& GetRules() {
    static const Rules rules;
    return rules;
}

// The receiver's rule from the separation: the distance from the receiver's centroid to the
// source's bounding sphere, in receiver radii. The three-point rule is exact for quadratics, so
// its error falls as separation^-3; these thresholds keep it below 5e-4 for separated pairs
// and spend the finest rule where the kernel is singular (docs/radiosity.md has the table).
int QuadratureLevel(double separation) {
    if (separation >= 8) return 0;
    if (separation >= 3) return 1;
    if (separation >= 1) return 2;
    return 3;
}

// Geometry of a side in render space ---------------------------------------------------------

Vec3d PointOf(const SideGeometry& g, const std::array<double, 3>& w) {
    return g.p[0] * w[0] + g.p[1] * w[1] + g.p[2] * w[2];
}

SurfacePoint RayPointOf(const EmbreeScene& scene, const PatchMesh& mesh, const SideGeometry& g,
                        const std::array<double, 3>& w) {
    const PatchMesh::Patch& patch = mesh.patches()[size_t(g.patch)];
    const auto [b1, b2] = mesh.TriangleBarycentrics(g.patch, w);
    return scene.TrianglePoint(patch.mesh, patch.primitive, float(b1), float(b2), 0);
}

// Form factors of one pair -------------------------------------------------------------------

// The source triangle clipped to the receiver point's hemisphere, then the contour integral.
double ClippedFormFactor(const Vec3d& x, const Vec3d& n, const std::array<Vec3d, 3>& source) {
    std::array<double, 3> d;
    int behind = 0;
    for (size_t k = 0; k < 3; ++k) {
        d[k] = Dot(n, source[k] - x);
        behind += d[k] < 0;
    }
    if (behind == 0) return PointToPolygonFormFactor(x, n, source);
    if (behind == 3) return 0;
    std::array<Vec3d, 4> clipped;
    size_t count = 0;
    for (size_t k = 0; k < 3; ++k) {
        const size_t next = (k + 1) % 3;
        if (d[k] >= 0) clipped[count++] = source[k];
        if ((d[k] >= 0) != (d[next] >= 0)) {
            clipped[count++] = source[k] + (source[next] - source[k]) * (d[k] / (d[k] - d[next]));
        }
    }
    return PointToPolygonFormFactor(x, n, std::span<const Vec3d>(clipped.data(), count));
}

// Unoccluded F from receiver to source with the receiver's rule at `level`.
double UnoccludedFormFactor(const SideGeometry& receiver, const SideGeometry& source, int level) {
    double f = 0;
    for (const Node& node : GetRules().quadrature[size_t(level)]) {
        const Vec3d x = PointOf(receiver, node.w);
        // The source side faces away from this point when its plane cuts the receiver.
        if (Dot(source.n, x - source.c) <= 0) continue;
        f += node.weight * ClippedFormFactor(x, receiver.n, source.p);
    }
    return f;
}

bool Facing(const SideGeometry& a, const SideGeometry& b, double epsilon) {
    auto in_front = [epsilon](const SideGeometry& of, const SideGeometry& plane) {
        for (const Vec3d& q : of.p) {
            if (Dot(plane.n, q - plane.c) > epsilon) return true;
        }
        return false;
    };
    return in_front(b, a) && in_front(a, b);
}

// Groups and blocks ---------------------------------------------------------------------------

std::vector<PatchGroup> MakeGroups(const PatchMesh& mesh, int32_t group_size) {
    std::vector<PatchGroup> groups;
    const auto& sides = mesh.sides();
    for (int32_t s = 0; s < int32_t(sides.size()); ++s) {
        const PatchMesh::Side& side = sides[size_t(s)];
        const bool same_surface = !groups.empty() && groups.back().size() < group_size &&
                                  mesh.patches()[size_t(side.patch)].mesh ==
                                      mesh.patches()[size_t(sides[size_t(s - 1)].patch)].mesh &&
                                  side.back == sides[size_t(s - 1)].back;
        if (same_surface) {
            groups.back().end = s + 1;
        } else {
            groups.push_back({s, s + 1});
        }
    }
    return groups;
}

// A group whose sides all lie in one plane sees nothing behind or on that plane.
struct GroupPlane {
    bool planar = false;
    Vec3d n, p;
};

GroupPlane PlaneOf(const PatchGroup& group, const std::vector<SideGeometry>& sides,
                   double epsilon) {
    const SideGeometry& first = sides[size_t(group.begin)];
    GroupPlane plane{true, first.n, first.c};
    for (int32_t s = group.begin; s < group.end && plane.planar; ++s) {
        const SideGeometry& g = sides[size_t(s)];
        plane.planar = Dot(g.n, first.n) > 1 - 1e-12;
        for (const Vec3d& q : g.p) plane.planar &= std::abs(Dot(first.n, q - first.c)) <= epsilon;
    }
    return plane;
}

bool AllBehind(const PatchGroup& group, const std::vector<SideGeometry>& sides,
               const GroupPlane& plane, double epsilon) {
    if (!plane.planar) return false;
    for (int32_t s = group.begin; s < group.end; ++s) {
        for (const Vec3d& q : sides[size_t(s)].p) {
            if (Dot(plane.n, q - plane.p) > epsilon) return false;
        }
    }
    return true;
}

// The dense block shrunk to the rows and columns holding non-zeros; empty if all are zero.
FormFactorBlock ShrinkBlock(int32_t row_group, int32_t col_group, const PatchGroup& rows,
                            const PatchGroup& cols, const std::vector<float>& dense) {
    FormFactorBlock block{row_group, col_group, rows.end, rows.begin, cols.end, cols.begin, {}};
    const int32_t width = cols.size();
    for (int32_t r = 0; r < rows.size(); ++r) {
        for (int32_t c = 0; c < width; ++c) {
            if (dense[size_t(r) * size_t(width) + size_t(c)] == 0) continue;
            block.row_begin = std::min(block.row_begin, rows.begin + r);
            block.row_end = std::max(block.row_end, rows.begin + r + 1);
            block.col_begin = std::min(block.col_begin, cols.begin + c);
            block.col_end = std::max(block.col_end, cols.begin + c + 1);
        }
    }
    if (block.row_begin >= block.row_end) return {row_group, col_group, 0, 0, 0, 0, {}};
    block.values.reserve(size_t(block.row_end - block.row_begin) * size_t(block.cols()));
    for (int32_t r = block.row_begin; r < block.row_end; ++r) {
        const float* row = &dense[size_t(r - rows.begin) * size_t(width)];
        block.values.insert(block.values.end(), row + (block.col_begin - cols.begin),
                            row + (block.col_end - cols.begin));
    }
    return block;
}

// Logs at most every few seconds, from whichever worker passes the deadline first.
class ProgressLog {
  public:
    explicit ProgressLog(int64_t total) : total_(total), start_(Clock::now()) {}

    void Add(int64_t work) {
        const int64_t done = done_.fetch_add(work) + work;
        const int64_t now = Elapsed();
        int64_t next = next_log_ms_.load();
        if (now < next || !next_log_ms_.compare_exchange_strong(next, now + kIntervalMs)) return;
        NamedLogger("radiosity")
            ->info("form factors: {:.0f}% after {:.0f} s", 100.0 * double(done) / total_,
                   now / 1000.0);
    }

  private:
    using Clock = std::chrono::steady_clock;
    static constexpr int64_t kIntervalMs = 5000;
    int64_t Elapsed() const {
        return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start_).count();
    }

    int64_t total_;
    Clock::time_point start_;
    std::atomic<int64_t> done_{0};
    std::atomic<int64_t> next_log_ms_{kIntervalMs};
};

// Reuse of another mesh's form factors -------------------------------------------------------

// A pair's form factors are a function of the two sides alone: their patches' corners (grid
// points of their scene triangles, placed by the same arithmetic in any mesh of that
// subdivision), normals, quadrature and ray levels, and rays into the one Embree scene; the pair
// is evaluated from its lower side index, and unsplit patches keep their order. Groups only
// decide which pairs are evaluated at all: a pair of groups culled as unable to see each other
// stores zeros without evaluating them, so a value is reused only from an evaluated pair.
class PreviousPairs {
  public:
    PreviousPairs(const PatchMesh& mesh, const MeshFormFactors& previous) {
        if (previous.mesh == nullptr || previous.form_factors == nullptr) return;
        const PatchMesh& old_mesh = *previous.mesh;
        form_factors_ = previous.form_factors;
        std::vector<std::pair<PatchCell, int64_t>> cells;
        cells.reserve(old_mesh.patches().size());
        for (int64_t p = 0; p < int64_t(old_mesh.patches().size()); ++p) {
            cells.push_back({old_mesh.Cell(p), p});
        }
        std::sort(cells.begin(), cells.end());
        side_.assign(mesh.sides().size(), -1);
        for (size_t s = 0; s < side_.size(); ++s) {
            const PatchMesh::Side& side = mesh.sides()[s];
            const PatchCell cell = mesh.Cell(side.patch);
            // The same cell of a triangle subdivided otherwise is another patch.
            if (old_mesh.Subdivision(cell.mesh, cell.primitive) !=
                mesh.Subdivision(cell.mesh, cell.primitive)) {
                continue;
            }
            const auto it =
                std::lower_bound(cells.begin(), cells.end(), std::pair(cell, int64_t(0)));
            if (it == cells.end() || it->first != cell) continue;
            side_[s] = old_mesh.patches()[size_t(it->second)].sides[side.back ? 1 : 0];
        }
        const FormFactors& old = *form_factors_;
        groups_ = int32_t(old.groups().size());
        group_of_.resize(size_t(old.size()));
        for (int32_t g = 0; g < groups_; ++g) {
            const PatchGroup& group = old.groups()[size_t(g)];
            std::fill(group_of_.begin() + group.begin, group_of_.begin() + group.end, g);
        }
        block_.assign(size_t(groups_) * size_t(groups_), kCulled);
        for (int32_t r = 0; r < groups_; ++r) {
            for (int32_t c = 0; c < groups_; ++c) {
                if (old.Evaluated(r, c)) block_[size_t(r) * size_t(groups_) + size_t(c)] = kZero;
            }
        }
        for (int32_t b = 0; b < int32_t(old.blocks().size()); ++b) {
            const FormFactorBlock& block = old.blocks()[size_t(b)];
            block_[size_t(block.row_group) * size_t(groups_) + size_t(block.col_group)] = b;
        }
    }

    // F_ab and F_ba (a < b) as the previous mesh's evaluation of the same pair left them; false
    // if a patch is new, the pair was not evaluated there, or the previous mesh ordered its sides
    // the other way (then the rays would have run the other way too).
    bool Find(int32_t a, int32_t b, float& ab, float& ba) const {
        if (form_factors_ == nullptr) return false;
        const int32_t oa = side_[size_t(a)], ob = side_[size_t(b)];
        if (oa < 0 || ob < 0 || oa >= ob) return false;
        const int32_t ga = group_of_[size_t(oa)], gb = group_of_[size_t(ob)];
        const int32_t forward = block_[size_t(ga) * size_t(groups_) + size_t(gb)];
        const int32_t backward = block_[size_t(gb) * size_t(groups_) + size_t(ga)];
        if (forward == kCulled || backward == kCulled) return false;
        ab = Value(forward, oa, ob);
        ba = Value(backward, ob, oa);
        return true;
    }

  private:
    static constexpr int32_t kCulled = -2, kZero = -1;

    float Value(int32_t block, int32_t row, int32_t col) const {
        if (block == kZero) return 0;
        const FormFactorBlock& b = form_factors_->blocks()[size_t(block)];
        const bool inside =
            row >= b.row_begin && row < b.row_end && col >= b.col_begin && col < b.col_end;
        return inside ? b.at(row, col) : 0.0f;
    }

    const FormFactors* form_factors_ = nullptr;
    std::vector<int32_t> side_;      // per side: the previous mesh's side on the same cell, or -1
    int32_t groups_ = 0;             // of the previous form factors
    std::vector<int32_t> group_of_;  // per previous side
    std::vector<int32_t> block_;     // per pair of previous groups: index into blocks(), or
                                     // kZero (evaluated, all zero) or kCulled
};

}  // namespace

std::vector<SideGeometry> SideGeometries(const EmbreeScene& scene, const PatchMesh& mesh) {
    std::vector<SideGeometry> sides(mesh.sides().size());
    for (size_t s = 0; s < sides.size(); ++s) {
        SideGeometry& g = sides[s];
        g.patch = mesh.sides()[s].patch;
        const PatchMesh::Patch& patch = mesh.patches()[size_t(g.patch)];
        for (size_t c = 0; c < 3; ++c) g.p[c] = mesh.vertices()[patch.vertices[c]] - scene.origin();
        g.n = mesh.SideNormal(int32_t(s));
        g.c = (g.p[0] + g.p[1] + g.p[2]) / 3.0;
        for (const Vec3d& q : g.p) g.radius = std::max(g.radius, Length(q - g.c));
        g.centre = RayPointOf(scene, mesh, g, {1.0 / 3, 1.0 / 3, 1.0 / 3});
    }
    return sides;
}

PairEvaluator::PairEvaluator(const EmbreeScene& scene, const PatchMesh& mesh)
    : scene_(scene), mesh_(mesh), sides_(SideGeometries(scene, mesh)) {
    const auto [lo, hi] = scene.scene().Bounds();
    epsilon_ = 1e-6 * Length(hi - lo);
}

PairFormFactors PairEvaluator::Evaluate(int32_t ia, int32_t ib, bool ab, bool ba) const {
    const SideGeometry &a = sides_[size_t(ia)], &b = sides_[size_t(ib)];
    if (!Facing(a, b, epsilon_)) return {};
    const double distance = Length(a.c - b.c);
    const int level_a = QuadratureLevel((distance - b.radius) / a.radius);
    const int level_b = QuadratureLevel((distance - a.radius) / b.radius);
    const int ray_level = std::clamp(std::max(level_a, level_b) - 1, 0, kMaxRayLevel);
    const auto& points = GetRules().rays[size_t(ray_level)];
    const int n = int(points.size());
    int visible = 0;
    for (int i = 0; i < n; ++i) {
        if (n == 1) {
            visible += !scene_.Occluded(SpawnRayTo(a.centre, b.centre));
            continue;
        }
        // A fixed scramble pairs each point on a with a different region of b.
        const int j = (i * (n / 2 + 1) + n / 4) % n;
        const SurfacePoint pa = RayPointOf(scene_, mesh_, a, points[size_t(i)]);
        const SurfacePoint pb = RayPointOf(scene_, mesh_, b, points[size_t(j)]);
        visible += !scene_.Occluded(SpawnRayTo(pa, pb));
    }
    PairFormFactors f;
    f.rays = n;
    if (visible == 0) return f;
    const double v = double(visible) / n;
    if (ab) f.ab = v * UnoccludedFormFactor(a, b, level_a);
    if (ba) f.ba = v * UnoccludedFormFactor(b, a, level_b);
    return f;
}

double PointToPolygonFormFactor(const Vec3d& x, const Vec3d& n, std::span<const Vec3d> polygon) {
    if (polygon.size() < 3) return 0;
    auto unit = [&x](const Vec3d& p) {
        const Vec3d d = p - x;
        return d * (1 / std::sqrt(LengthSquared(d)));
    };
    const Vec3d first = unit(polygon[0]);
    Vec3d a = first;
    double sum = 0;
    for (size_t k = 0; k < polygon.size(); ++k) {
        const Vec3d b = k + 1 < polygon.size() ? unit(polygon[k + 1]) : first;
        const Vec3d c = Cross(a, b);
        const double sin2 = LengthSquared(c);
        // A zero-length edge, or one whose line passes through x, subtends no area.
        if (sin2 > 0) sum += AngleOverSine(sin2, Dot(a, b)) * Dot(n, c);
        a = b;
    }
    return std::abs(sum) / (2 * std::numbers::pi);
}

FormFactors::FormFactors(int32_t sides, std::vector<PatchGroup> groups,
                         std::vector<FormFactorBlock> blocks, std::vector<bool> evaluated,
                         const FormFactorWork& work)
    : sides_(sides),
      groups_(std::move(groups)),
      blocks_(std::move(blocks)),
      evaluated_(std::move(evaluated)),
      work_(work) {
    std::sort(blocks_.begin(), blocks_.end(), [](const auto& a, const auto& b) {
        return std::pair(a.row_group, a.col_group) < std::pair(b.row_group, b.col_group);
    });
    const size_t g = groups_.size();
    row_start_.assign(g + 1, 0);
    col_start_.assign(g + 1, 0);
    for (const FormFactorBlock& b : blocks_) {
        ++row_start_[size_t(b.row_group) + 1];
        ++col_start_[size_t(b.col_group) + 1];
        for (float f : b.values) nonzeros_ += f != 0;
        bytes_ += b.values.size() * sizeof(float) + sizeof(FormFactorBlock);
    }
    for (size_t i = 0; i < g; ++i) {
        row_start_[i + 1] += row_start_[i];
        col_start_[i + 1] += col_start_[i];
    }
    col_blocks_.resize(blocks_.size());
    std::vector<int32_t> fill(col_start_.begin(), col_start_.end() - 1);
    for (int32_t i = 0; i < int32_t(blocks_.size()); ++i) {
        col_blocks_[size_t(fill[size_t(blocks_[size_t(i)].col_group)]++)] = i;
    }
    bytes_ += (row_start_.size() + col_start_.size() + col_blocks_.size()) * sizeof(int32_t) +
              groups_.size() * sizeof(PatchGroup) + evaluated_.size() / 8;
}

std::span<const FormFactorBlock> FormFactors::RowBlocks(int32_t group) const {
    return std::span<const FormFactorBlock>(blocks_).subspan(
        size_t(row_start_[size_t(group)]),
        size_t(row_start_[size_t(group) + 1] - row_start_[size_t(group)]));
}

std::span<const int32_t> FormFactors::ColumnBlocks(int32_t group) const {
    return std::span<const int32_t>(col_blocks_)
        .subspan(size_t(col_start_[size_t(group)]),
                 size_t(col_start_[size_t(group) + 1] - col_start_[size_t(group)]));
}

int32_t FormFactors::GroupOf(int32_t side) const {
    const auto it = std::upper_bound(groups_.begin(), groups_.end(), side,
                                     [](int32_t s, const PatchGroup& g) { return s < g.begin; });
    return int32_t(it - groups_.begin()) - 1;
}

float FormFactors::At(int32_t i, int32_t j) const {
    const int32_t gj = GroupOf(j);
    for (const FormFactorBlock& block : RowBlocks(GroupOf(i))) {
        if (block.col_group != gj) continue;
        if (i < block.row_begin || i >= block.row_end || j < block.col_begin ||
            j >= block.col_end) {
            return 0;
        }
        return block.at(i, j);
    }
    return 0;
}

double FormFactors::RowSum(int32_t i) const {
    double sum = 0;
    for (const FormFactorBlock& block : RowBlocks(GroupOf(i))) {
        if (i < block.row_begin || i >= block.row_end) continue;
        for (int32_t j = block.col_begin; j < block.col_end; ++j) sum += block.at(i, j);
    }
    return sum;
}

std::pair<int32_t, int32_t> ChunkGroups(int32_t groups, int chunk, int chunks) {
    // Chunk j has weight 3n - 2j: chunks k..n-1 hold (n - k)(2n - k + 1) of the n (2n + 1)
    // parts. Counting from the end rounds the remainder into the first chunks, so a few groups
    // go first, not last.
    const int64_t n = std::max(chunks, 1);
    const auto at = [&](int64_t k) {
        return int32_t(groups - int64_t(groups) * (n - k) * (2 * n - k + 1) / (n * (2 * n + 1)));
    };
    return {at(chunk), at(chunk + 1)};
}

FormFactors ComputeFormFactors(const EmbreeScene& scene, const PatchMesh& mesh,
                               const FormFactorOptions& options) {
    const PairEvaluator evaluator(scene, mesh);
    const PreviousPairs previous(mesh, options.previous);
    const std::vector<SideGeometry>& sides = evaluator.sides();
    std::vector<PatchGroup> groups = MakeGroups(mesh, std::max(1, options.group_size));
    std::vector<GroupPlane> planes;
    for (const PatchGroup& g : groups) planes.push_back(PlaneOf(g, sides, evaluator.epsilon()));
    const auto [row_begin, row_end] =
        ChunkGroups(int32_t(groups.size()), options.chunk, options.chunks);
    auto wanted = [&](int32_t g) { return g >= row_begin && g < row_end; };

    // Unordered pairs of groups that may see each other; each task fills both blocks (those
    // of wanted rows).
    std::vector<std::pair<int32_t, int32_t>> tasks;
    std::vector<bool> evaluated(groups.size() * groups.size(), false);
    int64_t total_work = 0;
    auto cancelled = [&] { return CancelRequested(options.cancel); };
    for (int32_t i = 0; i < int32_t(groups.size()) && !cancelled(); ++i) {
        for (int32_t j = i; j < int32_t(groups.size()); ++j) {
            if (!wanted(i) && !wanted(j)) continue;
            if (i == j && planes[size_t(i)].planar) continue;
            const double eps = evaluator.epsilon();
            if (AllBehind(groups[size_t(j)], sides, planes[size_t(i)], eps) ||
                AllBehind(groups[size_t(i)], sides, planes[size_t(j)], eps)) {
                continue;
            }
            tasks.push_back({i, j});
            evaluated[size_t(i) * groups.size() + size_t(j)] = wanted(i);
            evaluated[size_t(j) * groups.size() + size_t(i)] = wanted(j);
            total_work += int64_t(groups[size_t(i)].size()) * groups[size_t(j)].size();
        }
    }

    std::vector<std::array<FormFactorBlock, 2>> results(tasks.size());
    std::vector<FormFactorWork> task_work(tasks.size());
    ProgressLog progress(std::max<int64_t>(total_work, 1));
    tbb::parallel_for(size_t(0), tasks.size(), [&](size_t t) {
        if (cancelled()) return;
        const auto [gi, gj] = tasks[t];
        const PatchGroup &rows = groups[size_t(gi)], &cols = groups[size_t(gj)];
        std::vector<float> ij(size_t(rows.size()) * size_t(cols.size()), 0.0f);
        std::vector<float> ji(gi == gj ? 0 : ij.size(), 0.0f);
        FormFactorWork& work = task_work[t];
        for (int32_t a = rows.begin; a < rows.end; ++a) {
            if (cancelled()) return;  // a pair of large groups is many rays
            for (int32_t b = gi == gj ? a + 1 : cols.begin; b < cols.end; ++b) {
                float ab = 0, ba = 0;
                if (previous.Find(a, b, ab, ba)) {
                    ++work.reused_pairs;
                } else {
                    const PairFormFactors f = evaluator.Evaluate(a, b, wanted(gi), wanted(gj));
                    ++work.pairs;
                    work.rays += f.rays;
                    ab = float(f.ab);
                    ba = float(f.ba);
                }
                const size_t ra = size_t(a - rows.begin), cb = size_t(b - cols.begin);
                ij[ra * size_t(cols.size()) + cb] = ab;
                if (gi == gj) {
                    ij[cb * size_t(cols.size()) + ra] = ba;
                } else {
                    ji[cb * size_t(rows.size()) + ra] = ba;
                }
            }
        }
        if (wanted(gi)) results[t][0] = ShrinkBlock(gi, gj, rows, cols, ij);
        if (gi != gj && wanted(gj)) results[t][1] = ShrinkBlock(gj, gi, cols, rows, ji);
        progress.Add(int64_t(rows.size()) * cols.size());
    });

    std::vector<FormFactorBlock> blocks;
    FormFactorWork work;
    for (size_t t = 0; t < results.size(); ++t) {
        work.rays += task_work[t].rays;
        work.pairs += task_work[t].pairs;
        work.reused_pairs += task_work[t].reused_pairs;
        for (FormFactorBlock& b : results[t]) {
            if (!b.values.empty()) blocks.push_back(std::move(b));
        }
    }
    return FormFactors(int32_t(sides.size()), std::move(groups), std::move(blocks),
                       std::move(evaluated), work);
}

namespace {

// Directions per quadrature point for a sky (cosine-weighted) and a sun disk (uniform in its
// cone): with 12 points a side, 768 and 192.
constexpr int kSkyDirections = 64;
constexpr int kSunDirections = 16;

// Direction sample d of quadrature point k: point k takes the Sobol points [k n, (k + 1) n), each
// such run a stratified net, and the side's points together a longer prefix of the sequence.
Vec2 DirectionSample(int k, int d, int n) {
    const uint32_t index = uint32_t(k * n + d);
    return {float(SobolDimension0(index)) * 0x1p-32f, float(SobolDimension1(index)) * 0x1p-32f};
}

// The irradiance one light puts on a side: the quadrature's weighted sum of `at(x, from)` over
// the side's points, at least 12 so that a shadow edge across the patch is resolved.
template <typename At>
Rgb SideAverage(const EmbreeScene& scene, const PatchMesh& mesh, const SideGeometry& g, int level,
                const At& at) {
    Rgb e;
    const auto& nodes = GetRules().quadrature[size_t(std::max(1, level))];
    for (size_t k = 0; k < nodes.size(); ++k) {
        const Vec3d x = PointOf(g, nodes[k].w);
        e += at(x, RayPointOf(scene, mesh, g, nodes[k].w), int(k)) * float(nodes[k].weight);
    }
    return e;
}

}  // namespace

std::vector<Rgb> DirectIrradiance(const EmbreeScene& scene, const PatchMesh& mesh,
                                  const std::atomic<bool>* cancel) {
    const Scene& s = scene.scene();
    const std::vector<SideGeometry> sides = SideGeometries(scene, mesh);
    std::vector<Rgb> irradiance(sides.size());
    const LightSampler lights(scene, LightStrategy::kPower);
    std::vector<size_t> delta;
    for (size_t i = 0; i < lights.size(); ++i) {
        if (lights.IsDeltaLight(i)) delta.push_back(i);
    }
    std::vector<SunDisk> suns;
    for (const DirectionalLight& light : s.directional_lights) {
        if (const std::optional<SunDisk> sun = SunDiskOf(light)) suns.push_back(*sun);
    }
    std::optional<EnvironmentEmitter> sky;
    if (s.environment) sky.emplace(*s.environment);
    if (delta.empty() && suns.empty() && !sky) return irradiance;
    tbb::parallel_for(size_t(0), sides.size(), [&](size_t i) {
        // A sky costs hundreds of rays a side: a cancel must not wait for millions of sides.
        if (cancel && cancel->load(std::memory_order_relaxed)) return;
        const SideGeometry& g = sides[i];
        const Vec3 n(g.n);
        Rgb& e = irradiance[i];
        for (const size_t light : delta) {
            const std::optional<LightSample> centre = lights.SampleDeltaLight(light, Vec3(g.c), 0);
            const int level = centre && !centre->at_infinity
                                  ? QuadratureLevel(Length(Vec3d(centre->point.p) - g.c) / g.radius)
                                  : 1;
            e += SideAverage(scene, mesh, g, level,
                             [&](const Vec3d& x, const SurfacePoint& from, int) {
                                 const std::optional<LightSample> ls =
                                     lights.SampleDeltaLight(light, Vec3(x), 0);
                                 if (!ls) return Rgb();
                                 const float cosine = Dot(n, ls->wi);
                                 if (cosine <= 0 || scene.Occluded(SpawnRayTo(from, ls->point)))
                                     return Rgb();
                                 return ls->radiance * cosine;
                             });
        }
        for (const SunDisk& sun : suns) {
            const Frame frame = Frame::FromNormal(sun.axis);
            const float solid_angle = 2 * std::numbers::pi_v<float> * sun.one_minus_cos;
            e += SideAverage(scene, mesh, g, 1, [&](const Vec3d&, const SurfacePoint& from, int k) {
                float sum = 0;
                for (int d = 0; d < kSunDirections; ++d) {
                    const Vec2 u = DirectionSample(k, d, kSunDirections);
                    const float one_minus_cos = u.x * sun.one_minus_cos;
                    const float sin =
                        std::sqrt(std::max(0.0f, one_minus_cos * (2 - one_minus_cos)));
                    const float phi = 2 * std::numbers::pi_v<float> * u.y;
                    const Vec3 w = frame.FromLocal(
                        {sin * std::cos(phi), sin * std::sin(phi), 1 - one_minus_cos});
                    const float cosine = Dot(n, w);
                    if (cosine > 0 && !scene.Occluded(SpawnRay(from, w))) sum += cosine;
                }
                return sun.radiance * (sum * solid_angle / kSunDirections);
            });
        }
        if (sky) {
            const Frame frame = Frame::FromNormal(n);
            e += SideAverage(scene, mesh, g, 1, [&](const Vec3d&, const SurfacePoint& from, int k) {
                Rgb sum;
                for (int d = 0; d < kSkyDirections; ++d) {
                    const Vec3 w = frame.FromLocal(
                        SampleCosineHemisphere(DirectionSample(k, d, kSkyDirections)));
                    if (!scene.Occluded(SpawnRay(from, w))) sum += sky->Le(w);
                }
                return sum * (std::numbers::pi_v<float> / kSkyDirections);
            });
        }
    });
    return irradiance;
}

}  // namespace lf
