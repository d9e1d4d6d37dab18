#include "lf/core/patch_mesh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <compare>
#include <limits>
#include <map>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/cancel.h"

namespace lf {

namespace {

// Far beyond what an O(n^2) radiosity solve can handle; stops a typo from exhausting memory.
constexpr int64_t kMaxPatches = int64_t(1) << 26;

int64_t PatchCount(const std::vector<double>& longest_edges, double size) {
    int64_t count = 0;
    for (double edge : longest_edges) {
        const double k = std::max(1.0, std::ceil(edge / size));
        if (k * k > double(kMaxPatches)) return kMaxPatches + 1;
        count += int64_t(k) * int64_t(k);
        if (count > kMaxPatches) return kMaxPatches + 1;
    }
    return count;
}

// The largest patch size is one patch per triangle; halving finds a size that is too fine,
// then bisection the coarsest size whose count still fits under the target. Both loops are
// bounded whatever the input: a target of at most kMaxPatches is exceeded after about 14
// halvings of any edge that is not degenerate, and for one that is (every edge 0) the halving
// gives up after kMaxHalvings.
double PatchSizeForCount(const std::vector<double>& longest_edges, int64_t target) {
    constexpr int kMaxHalvings = 64;
    double hi = *std::max_element(longest_edges.begin(), longest_edges.end());
    if (PatchCount(longest_edges, hi) >= target) return hi;
    double lo = hi;
    for (int halvings = 0; PatchCount(longest_edges, lo) <= target; ++halvings) {
        if (halvings == kMaxHalvings) return hi;
        lo *= 0.5;
    }
    for (int iteration = 0; iteration < 64; ++iteration) {
        const double mid = std::sqrt(lo * hi);
        if (mid <= lo || mid >= hi) break;
        (PatchCount(longest_edges, mid) <= target ? hi : lo) = mid;
    }
    return hi;
}

absl::Status MeshingCancelled() { return absl::CancelledError("radiosity: meshing cancelled"); }

double LongestEdge(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    return std::sqrt(std::max({LengthSquared(b - a), LengthSquared(c - b), LengthSquared(a - c)}));
}

// Vertices on a scene triangle's corners and edges are shared with the neighbours that use the
// same subdivision along that edge: keyed by the scene vertex ids, never by position.
struct VertexKey {
    uint32_t a, b;        // corner: (id, id); edge: (smaller id, larger id)
    int32_t k, position;  // edge: subdivision and position counted from `a`
    auto operator<=>(const VertexKey&) const = default;
};

class SideRule {
  public:
    explicit SideRule(const Scene& scene) : scene_(scene) {
        const auto [lo, hi] = scene.Bounds();
        epsilon_ = std::max(1e-6 * Length(hi - lo), std::numeric_limits<double>::min());
        for (const TriangleMesh& mesh : scene.meshes) {
            Vec3d mlo = mesh.positions.front(), mhi = mlo;
            for (const Vec3d& p : mesh.positions) {
                mlo = Min(mlo, p);
                mhi = Max(mhi, p);
            }
            mesh_bounds_.push_back({mlo, mhi});
        }
    }

    // True if a light can shine on the plane through p with normal n from its front (a point
    // or spot light in front of it, a directional light or sun disk towards it, any sky) or a
    // vertex of the scene lies strictly in front of it: only then can light arrive there.
    bool SomethingInFront(const Vec3d& p, const Vec3d& n) const {
        if (scene_.environment) return true;
        for (const PointLight& light : scene_.point_lights) {
            if (Dot(light.position - p, n) > epsilon_) return true;
        }
        for (const SpotLight& light : scene_.spot_lights) {
            if (Dot(light.position - p, n) > epsilon_) return true;
        }
        for (const DirectionalLight& light : scene_.directional_lights) {
            // Towards the light lies -direction; a sun disk reaches sin(radius) below it.
            if (-Dot(light.direction, n) > -std::sin(light.angular_diameter / 2)) return true;
        }
        for (size_t m = 0; m < scene_.meshes.size(); ++m) {
            const auto& [lo, hi] = mesh_bounds_[m];
            const Vec3d farthest(n.x > 0 ? hi.x : lo.x, n.y > 0 ? hi.y : lo.y,
                                 n.z > 0 ? hi.z : lo.z);
            if (Dot(farthest - p, n) <= epsilon_) continue;
            for (const Vec3d& q : scene_.meshes[m].positions) {
                if (Dot(q - p, n) > epsilon_) return true;
            }
        }
        return false;
    }

  private:
    const Scene& scene_;
    double epsilon_ = 0;
    std::vector<std::pair<Vec3d, Vec3d>> mesh_bounds_;
};

// The id of a grid cell given by its corners, in any order.
PatchCell CellId(int32_t mesh, int32_t primitive, int level, const GridTriangle& cell) {
    PatchCell id{mesh,
                 primitive,
                 level,
                 std::min({cell[0][0], cell[1][0], cell[2][0]}),
                 std::min({cell[0][1], cell[1][1], cell[2][1]}),
                 false};
    for (const auto& corner : cell) id.up |= corner[0] == id.i && corner[1] == id.j;
    return id;
}

// The quarters of a cell in the grid one level finer: at its corners 0, 1, 2, then the middle
// (turned by 180°). Each keeps the cell's winding.
std::array<GridTriangle, 4> Quarters(const GridTriangle& c) {
    auto twice = [](const std::array<int32_t, 2>& a) {
        return std::array<int32_t, 2>{2 * a[0], 2 * a[1]};
    };
    auto mid = [](const std::array<int32_t, 2>& a, const std::array<int32_t, 2>& b) {
        return std::array<int32_t, 2>{a[0] + b[0], a[1] + b[1]};
    };
    const auto m01 = mid(c[0], c[1]), m12 = mid(c[1], c[2]), m20 = mid(c[2], c[0]);
    return {{{twice(c[0]), m01, m20},
             {m01, twice(c[1]), m12},
             {m20, m12, twice(c[2])},
             {m01, m12, m20}}};
}

// The quarter holding the point with weights w on a cell's corners, and its weights there (the
// inverse of the quarters' corner maps).
int Quarter(std::array<double, 3>& w) {
    for (int c = 0; c < 3; ++c) {
        if (w[size_t(c)] >= 0.5) {
            for (double& x : w) x *= 2;
            w[size_t(c)] -= 1;
            return c;
        }
    }
    w = {1 - 2 * w[2], 1 - 2 * w[0], 1 - 2 * w[1]};
    return 3;
}

// Rounding can put weights just below 0: clamped and renormalised, so they stay a convex
// combination.
void ClampWeights(std::array<double, 3>& w) {
    double sum = 0;
    for (double& x : w) sum += (x = std::max(x, 0.0));
    for (double& x : w) x /= sum;
}

}  // namespace

std::vector<GridTriangle> SubdivisionCells(int k) {
    std::vector<GridTriangle> cells;
    cells.reserve(size_t(k) * size_t(k));
    for (int j = 0; j < k; ++j) {
        for (int i = 0; i + j < k; ++i) {
            cells.push_back({{{i, j}, {i + 1, j}, {i, j + 1}}});
            if (i + j + 1 < k) cells.push_back({{{i + 1, j}, {i + 1, j + 1}, {i, j + 1}}});
        }
    }
    return cells;
}

bool MayReflectDiffusely(const Material& m) {
    switch (m.type) {
        case Material::Type::kLambert:
            return !m.reflectance.IsBlack();
        case Material::Type::kPrincipled:
            return !m.reflectance.IsBlack() && m.metallic < 1 && m.transmission < 1;
        default:
            return false;
    }
}

namespace {

// The material of every shape radiosity meshes, with the shape's name: meshes, then spheres
// (TessellateSpheres makes them meshes of the same material).
template <typename F>
void ForEachShapeMaterial(const Scene& scene, F&& f) {
    for (const TriangleMesh& mesh : scene.meshes) f(mesh.material, "mesh", mesh.name);
    for (const Sphere& sphere : scene.spheres) f(sphere.material, "sphere", sphere.name);
}

}  // namespace

std::string RadiosityLimitation(const Scene& scene) {
    std::string why;
    ForEachShapeMaterial(scene, [&](int material, const char* kind, const std::string& name) {
        if (!why.empty()) return;
        const Material& m = scene.materials[size_t(material)];
        const std::string what =
            absl::StrCat("material \"", m.name, "\" (", kind, " \"", name, "\") ");
        // An interface bounds a medium: light passes it unchanged, which a patch cannot.
        if (m.type == Material::Type::kInterface) {
            why = what + "is a medium interface, which radiosity does not model";
        } else if (m.alpha_mode == Material::AlphaMode::kMask) {
            // Cut-outs change what the patches see, not what they reflect.
            why = what + "has an alpha mask, which radiosity does not model";
        } else if (m.alpha_mode == Material::AlphaMode::kBlend) {
            why = what + "is alpha-blended, which radiosity does not model";
        } else if (!m.double_sided) {
            why = what + "is single-sided, which radiosity does not model";
        }
    });
    return why;
}

std::string RadiosityDrops(const Scene& scene) {
    // Per category, the used materials it applies to, each named once.
    struct Dropped {
        const char* what;
        std::vector<std::string> names;
    };
    std::array<Dropped, 6> dropped = {{{"no diffuse part (rendered black)", {}},
                                       {"specular reflection", {}},
                                       {"transmission", {}},
                                       {"clear coat", {}},
                                       {"sheen", {}},
                                       {"normal map", {}}}};
    std::vector<bool> seen(scene.materials.size(), false);
    ForEachShapeMaterial(scene, [&](int material, const char*, const std::string&) {
        if (seen[size_t(material)]) return;
        seen[size_t(material)] = true;
        const Material& m = scene.materials[size_t(material)];
        const std::string name = absl::StrCat("\"", m.name, "\"");
        const bool principled = m.type == Material::Type::kPrincipled;
        const bool diffuse = m.type == Material::Type::kLambert || principled;
        // A black lambert is black on purpose; a full metal or full transmission is not.
        if (!diffuse || (principled && !MayReflectDiffusely(m) && !m.reflectance.IsBlack())) {
            dropped[0].names.push_back(absl::StrCat(name, " (", MaterialTypeName(m.type), ")"));
        }
        if (principled && (m.specular > 0 || m.metallic > 0)) dropped[1].names.push_back(name);
        if (principled && m.transmission > 0) dropped[2].names.push_back(name);
        if (principled && m.clearcoat > 0) dropped[3].names.push_back(name);
        if (principled && !m.sheen_color.IsBlack()) dropped[4].names.push_back(name);
        if (diffuse && m.normal_texture.valid()) dropped[5].names.push_back(name);
    });
    std::string out;
    for (const Dropped& d : dropped) {
        if (d.names.empty()) continue;
        absl::StrAppend(&out, out.empty() ? "" : "; ", d.what, ": ", absl::StrJoin(d.names, ", "));
    }
    return out;
}

absl::Status RadiosityRefusal(const Scene& scene) {
    const std::string why = RadiosityLimitation(scene);
    if (why.empty()) return absl::OkStatus();
    return absl::InvalidArgumentError(
        absl::StrCat("radiosity: ", why, "; render it with --method path"));
}

absl::StatusOr<PatchMesh> PatchMesh::Build(const Scene& scene, const PatchMeshOptions& options) {
    auto cancelled = [&] { return CancelRequested(options.cancel); };
    if (absl::Status refused = RadiosityRefusal(scene); !refused.ok()) return refused;
    if (!scene.spheres.empty()) {
        return absl::InvalidArgumentError(
            absl::StrCat("radiosity: sphere \"", scene.spheres.front().name,
                         "\" was not meshed (lf/core/sphere_mesh.h TessellateSpheres meshes "
                         "spheres before the patch mesh is built)"));
    }
    if (!(options.patch_size >= 0) || (options.patch_size == 0 && options.patches <= 0)) {
        return absl::InvalidArgumentError(
            "radiosity: give a positive patch size or a positive patch count");
    }

    PatchMesh pm;
    std::vector<double> longest_edges;
    for (const TriangleMesh& mesh : scene.meshes) {
        pm.mesh_first_triangle_.push_back(int64_t(longest_edges.size()));
        double quad_edge = 0;
        for (const auto& t : mesh.triangles) {
            const double edge =
                LongestEdge(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]);
            longest_edges.push_back(edge);
            quad_edge = std::max(quad_edge, edge);
        }
        // Both halves of a quad share the diagonal: one subdivision keeps its vertices shared.
        if (mesh.is_quad) {
            std::fill(longest_edges.end() - int64_t(mesh.triangles.size()), longest_edges.end(),
                      quad_edge);
        }
    }
    if (longest_edges.empty()) return absl::InvalidArgumentError("radiosity: no triangles");
    // Before the search: a target above the limit could never be met, and would only make
    // the search look for a size it cannot find.
    if (options.patch_size <= 0 && (options.patches < 1 || options.patches > kMaxPatches)) {
        return absl::InvalidArgumentError(absl::StrCat("radiosity: target of ", options.patches,
                                                       " patches: expected 1 to ", kMaxPatches));
    }
    if (!(options.patch_size >= 0 && std::isfinite(options.patch_size))) {
        return absl::InvalidArgumentError(absl::StrCat("radiosity: patch size ", options.patch_size,
                                                       ": expected a finite size, 0 or more"));
    }

    pm.patch_size_ = options.patch_size > 0 ? options.patch_size
                                            : PatchSizeForCount(longest_edges, options.patches);
    if (const int64_t n = PatchCount(longest_edges, pm.patch_size_); n > kMaxPatches) {
        return absl::InvalidArgumentError(absl::StrCat("radiosity: patch size ", pm.patch_size_,
                                                       " gives more than ", kMaxPatches,
                                                       " patches"));
    }

    std::vector<PatchCell> split = options.split;
    std::sort(split.begin(), split.end());
    split.erase(std::unique(split.begin(), split.end()), split.end());
    // Checked first: a corrupt list must not nest the recursion below arbitrarily deep.
    for (const PatchCell& c : split) {
        if (c.level < 0 || c.level >= kMaxPatchLevel) {
            return absl::InvalidArgumentError(absl::StrCat(
                "radiosity: split cell of level ", c.level, " (at most ", kMaxPatchLevel - 1, ")"));
        }
    }
    std::vector<bool> split_seen(split.size(), false);

    // Subdivision: grid vertex (i, j) of a triangle with subdivision k is the point with
    // barycentrics b1 = i/k, b2 = j/k; at level l, b1 = i/K, b2 = j/K with K = k 2^l.
    pm.triangles_.resize(longest_edges.size());
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const TriangleMesh& mesh = scene.meshes[m];
        std::map<VertexKey, uint32_t> shared;
        auto shared_vertex = [&](const VertexKey& key, const Vec3d& p) {
            const auto [it, inserted] = shared.try_emplace(key, uint32_t(pm.vertices_.size()));
            if (inserted) pm.vertices_.push_back(p);
            return it->second;
        };
        auto edge_vertex = [&](uint32_t a, uint32_t b, int k, int position) {
            if (a > b) {
                std::swap(a, b);
                position = k - position;
            }
            const Vec3d& pa = mesh.positions[a];
            return shared_vertex({a, b, k, position},
                                 pa + (mesh.positions[b] - pa) * (double(position) / k));
        };
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            if (cancelled()) return MeshingCancelled();
            const auto& tri = mesh.triangles[t];
            const Vec3d &p0 = mesh.positions[tri[0]], &p1 = mesh.positions[tri[1]],
                        &p2 = mesh.positions[tri[2]];
            const size_t index = size_t(pm.mesh_first_triangle_[m]) + t;
            Triangle& info = pm.triangles_[index];
            const int k = int(std::max(1.0, std::ceil(longest_edges[index] / pm.patch_size_)));
            info.k = k;
            info.first_patch = int64_t(pm.patches_.size());
            info.first_node = int64_t(pm.nodes_.size());
            info.normal = Normalize(Cross(p1 - p0, p2 - p0));
            const double area = 0.5 * Length(Cross(p1 - p0, p2 - p0)) / (double(k) * k);

            // The vertex of grid point (i, j) of a grid of size K: on the scene triangle's
            // corners and edges shared with the neighbours that subdivide alike, inside it
            // shared between the triangle's cells.
            auto grid_vertex = [&](int K, int i, int j) {
                if (i == 0 && j == 0) return shared_vertex({tri[0], tri[0], 0, 0}, p0);
                if (i == K) return shared_vertex({tri[1], tri[1], 0, 0}, p1);
                if (j == K) return shared_vertex({tri[2], tri[2], 0, 0}, p2);
                if (j == 0) return edge_vertex(tri[0], tri[1], K, i);
                if (i == 0) return edge_vertex(tri[0], tri[2], K, j);
                if (i + j == K) return edge_vertex(tri[1], tri[2], K, j);
                return uint32_t(pm.vertices_.size());
            };
            // Row j of the grid holds k + 1 - j vertices.
            std::vector<uint32_t> grid;
            grid.reserve(size_t(k + 1) * (k + 2) / 2);
            for (int j = 0; j <= k; ++j) {
                if (cancelled()) return MeshingCancelled();
                for (int i = 0; i + j <= k; ++i) {
                    const uint32_t id = grid_vertex(k, i, j);
                    if (id == pm.vertices_.size()) {
                        const double b1 = double(i) / k, b2 = double(j) / k;
                        pm.vertices_.push_back(p0 * (1 - b1 - b2) + p1 * b1 + p2 * b2);
                    }
                    grid.push_back(id);
                }
            }
            auto at = [&](int i, int j) { return grid[size_t(j * (k + 1) - j * (j - 1) / 2 + i)]; };
            // Vertices of split cells: a point of level l with even coordinates is one of
            // level l - 1, so each point is created once, at its coarsest level.
            std::map<std::array<int32_t, 3>, uint32_t> fine;
            auto vertex = [&](int level, int i, int j) {
                while (level > 0 && i % 2 == 0 && j % 2 == 0) {
                    i /= 2;
                    j /= 2;
                    --level;
                }
                if (level == 0) return at(i, j);
                const auto [it, inserted] = fine.try_emplace({level, i, j}, 0);
                if (!inserted) return it->second;
                const int K = k << level;
                const uint32_t id = grid_vertex(K, i, j);
                if (id == pm.vertices_.size()) {
                    const double b1 = double(i) / K, b2 = double(j) / K;
                    pm.vertices_.push_back(p0 * (1 - b1 - b2) + p1 * b1 + p2 * b2);
                }
                return it->second = id;
            };
            // Cells in patch order, each split one replaced by its quarters (depth first).
            auto emit = [&](auto& self, int64_t node, const GridTriangle& cell, int level) -> void {
                const auto found = std::lower_bound(split.begin(), split.end(),
                                                    CellId(int32_t(m), int32_t(t), level, cell));
                if (found != split.end() && *found == CellId(int32_t(m), int32_t(t), level, cell)) {
                    split_seen[size_t(found - split.begin())] = true;
                    const int64_t first = int64_t(pm.nodes_.size());
                    pm.nodes_[size_t(node)] = ~first;
                    pm.nodes_.resize(pm.nodes_.size() + 4);
                    const std::array<GridTriangle, 4> quarters = Quarters(cell);
                    for (int q = 0; q < 4; ++q)
                        self(self, first + q, quarters[size_t(q)], level + 1);
                    return;
                }
                pm.nodes_[size_t(node)] = int64_t(pm.patches_.size());
                Patch patch;
                patch.mesh = int32_t(m);
                patch.primitive = int32_t(t);
                for (size_t c = 0; c < 3; ++c)
                    patch.vertices[c] = vertex(level, cell[c][0], cell[c][1]);
                // Exact: quarters of quarters differ from the coarse area by powers of two.
                patch.area = std::ldexp(area, -2 * level);
                patch.cell = cell;
                patch.level = level;
                pm.patches_.push_back(patch);
            };
            const std::vector<GridTriangle> cells = SubdivisionCells(k);
            pm.nodes_.resize(pm.nodes_.size() + cells.size());
            for (size_t c = 0; c < cells.size(); ++c) {
                if (c % 4096 == 0 && cancelled()) return MeshingCancelled();
                emit(emit, info.first_node + int64_t(c), cells[c], 0);
            }
            info.end_patch = int64_t(pm.patches_.size());
        }
    }
    for (size_t n = 0; n < split.size(); ++n) {
        if (split_seen[n]) continue;
        const PatchCell& c = split[n];
        return absl::InvalidArgumentError(
            absl::StrCat("radiosity: split cell (mesh ", c.mesh, ", triangle ", c.primitive,
                         ", level ", c.level, ", ", c.i, ", ", c.j, c.up ? ", up" : ", down",
                         ") is not a cell of the mesh or not inside a split cell"));
    }
    if (int64_t(pm.patches_.size()) > kMaxPatches) {
        return absl::InvalidArgumentError(
            absl::StrCat("radiosity: refinement gives more than ", kMaxPatches, " patches"));
    }
    pm.split_ = std::move(split);

    const SideRule rule(scene);
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const TriangleMesh& mesh = scene.meshes[m];
        const Material& material = scene.materials[size_t(mesh.material)];
        for (int back = 0; back < 2; ++back) {
            for (size_t t = 0; t < mesh.triangles.size(); ++t) {
                if (cancelled()) return MeshingCancelled();
                const Triangle& info = pm.triangles_[size_t(pm.mesh_first_triangle_[m]) + t];
                const Vec3d n = back ? -info.normal : info.normal;
                // A black side's radiosity is its emission, but its irradiance is shown.
                const bool needed =
                    ((!back || material.two_sided_emission) && material.IsEmissive()) ||
                    rule.SomethingInFront(mesh.positions[mesh.triangles[t][0]], n);
                if (!needed) continue;
                for (int64_t p = info.first_patch; p < info.end_patch; ++p) {
                    pm.patches_[size_t(p)].sides[size_t(back)] = int32_t(pm.sides_.size());
                    pm.sides_.push_back({int32_t(p), back == 1});
                }
            }
        }
    }
    return pm;
}

const Vec3d& PatchMesh::Normal(int64_t patch) const {
    const Patch& p = patches_[size_t(patch)];
    return triangle(p.mesh, p.primitive).normal;
}

Vec3d PatchMesh::SideNormal(int32_t side) const {
    const Side& s = sides_[size_t(side)];
    const Vec3d& n = Normal(s.patch);
    return s.back ? -n : n;
}

Vec3d PatchMesh::Centroid(int64_t patch) const {
    const Patch& p = patches_[size_t(patch)];
    return (vertices_[p.vertices[0]] + vertices_[p.vertices[1]] + vertices_[p.vertices[2]]) / 3.0;
}

PatchCell PatchMesh::Cell(int64_t patch) const {
    const Patch& p = patches_[size_t(patch)];
    return CellId(p.mesh, p.primitive, p.level, p.cell);
}

PatchPoint PatchMesh::Locate(int mesh, int primitive, double b1, double b2) const {
    const Triangle& info = triangle(mesh, primitive);
    const int k = info.k;
    const double x = std::clamp(b1, 0.0, 1.0) * k, y = std::clamp(b2, 0.0, 1.0) * k;
    const int j = std::clamp(int(y), 0, k - 1);
    // Rounding can put a point on the long edge just past it: it belongs to the last cell.
    const int i = std::clamp(int(x), 0, k - 1 - j);
    const double fx = x - i, fy = y - j;
    const bool upward = fx + fy <= 1 || i + j == k - 1;
    // Row j starts after 2kj - j^2 patches; upward and downward cells alternate along it.
    const int64_t local = int64_t(2 * k - j) * j + 2 * i + (upward ? 0 : 1);
    PatchPoint point;
    point.w = upward ? std::array<double, 3>{1 - fx - fy, fx, fy}
                     : std::array<double, 3>{1 - fy, fx + fy - 1, 1 - fx};
    ClampWeights(point.w);
    int64_t node = nodes_[size_t(info.first_node + local)];
    while (node < 0) {
        node = nodes_[size_t(~node + Quarter(point.w))];
        ClampWeights(point.w);
    }
    point.patch = node;
    return point;
}

std::array<double, 2> PatchMesh::TriangleBarycentrics(int64_t patch,
                                                      const std::array<double, 3>& w) const {
    const Patch& p = patches_[size_t(patch)];
    const double k = double(triangle(p.mesh, p.primitive).k << p.level);
    double b1 = 0, b2 = 0;
    for (size_t c = 0; c < 3; ++c) {
        b1 += w[c] * p.cell[c][0];
        b2 += w[c] * p.cell[c][1];
    }
    return {b1 / k, b2 / k};
}

}  // namespace lf
