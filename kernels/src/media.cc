#include "lf/kernels/media.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "lf/core/blackbody.h"

namespace lf {
namespace {

constexpr int kMajorantRes = 16;
constexpr int kLeTableSize = 1024;
constexpr float kMinMajorantFraction = 1e-2f;
// Below this a black body's visible radiance is negligible (and Planck's law underflows far
// below it): it emits 0.
constexpr double kMinGlowK = 500;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

// An affine map in float: render space to a grid's index space (or the majorant grid's).
struct FloatAffine {
    std::array<std::array<float, 4>, 3> m{};

    Vec3 ApplyLinear(const Vec3& v) const {
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    Vec3 Apply(const Vec3& p) const { return ApplyLinear(p) + Vec3(m[0][3], m[1][3], m[2][3]); }
};

// Render space (world minus origin) to `grid`'s index space, then each axis a mapped to
// (q[a] - offset[a]) / width[a]. The origin is added back in double, once.
FloatAffine RenderToIndex(const VolumeGrid& grid, const Vec3d& origin,
                          const Vec3d& offset = {0, 0, 0}, const Vec3d& width = {1, 1, 1}) {
    const Vec3d translation = grid.world_to_index.Apply(origin);
    FloatAffine a;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) a.m[r][c] = float(grid.world_to_index.m[r][c] / width[r]);
        a.m[r][3] = float((translation[r] - offset[r]) / width[r]);
    }
    return a;
}

float GridValue(const VolumeGrid& grid, const FloatAffine& to_index, const Vec3& p) {
    return grid.Lookup(Vec3d(to_index.Apply(p)));
}

// The lattice box grown by one point each way: the trilinear blend reaches the background
// only there, so outside [lo, hi] the density is the background.
std::pair<Vec3d, Vec3d> DensityBox(const VolumeGrid& grid) {
    return {
        Vec3d(grid.min[0] - 1, grid.min[1] - 1, grid.min[2] - 1),
        Vec3d(grid.min[0] + grid.size[0], grid.min[1] + grid.size[1], grid.min[2] + grid.size[2])};
}

// The 16^3 cells over [lo, hi], each holding the largest density of the lattice points whose
// trilinear footprint meets it (a point in [a, b] reads the points floor(a) .. floor(b) + 1),
// widened by a 1/64 voxel so that a point rounded into the neighbouring cell is still bound.
std::vector<float> BuildMajorants(const VolumeGrid& grid, const Vec3d& lo, const Vec3d& width) {
    constexpr double kSlack = 1.0 / 64;
    std::array<std::array<std::pair<int, int>, kMajorantRes>, 3> ranges;
    for (int a = 0; a < 3; ++a) {
        for (int c = 0; c < kMajorantRes; ++c) {
            ranges[size_t(a)][size_t(c)] = {
                int(std::floor(lo[a] + c * width[a] - kSlack)),
                int(std::floor(lo[a] + (c + 1) * width[a] + kSlack)) + 1};
        }
    }
    std::vector<float> cells(size_t(kMajorantRes) * kMajorantRes * kMajorantRes, 0.0f);
    for (int cz = 0; cz < kMajorantRes; ++cz) {
        for (int cy = 0; cy < kMajorantRes; ++cy) {
            for (int cx = 0; cx < kMajorantRes; ++cx) {
                float m = 0;
                const auto [x0, x1] = ranges[0][size_t(cx)];
                const auto [y0, y1] = ranges[1][size_t(cy)];
                const auto [z0, z1] = ranges[2][size_t(cz)];
                for (int z = z0; z <= z1; ++z) {
                    for (int y = y0; y <= y1; ++y) {
                        for (int x = x0; x <= x1; ++x) m = std::max(m, grid.At(x, y, z));
                    }
                }
                cells[(size_t(cz) * kMajorantRes + size_t(cy)) * kMajorantRes + size_t(cx)] = m;
            }
        }
    }
    return cells;
}

}  // namespace

// One medium as the estimators read it.
struct RenderMedium {
    Medium::Type type;
    Rgb sigma_a, sigma_s, sigma_t, emission;
    // kGrid: sigma_t per unit density with every channel at least kMinMajorantFraction of the
    // largest. A majorant may be any bound above sigma_t; a channel of sigma_t 0 (but not all)
    // would otherwise give its hero paths no collisions, and the others would then be attenuated
    // by their majorant, not their density: biased. With the floor they see null collisions.
    Rgb majorant_per_density;
    float g;
    bool emissive;
    // kGrid: each grid with its map from render space.
    std::shared_ptr<const VolumeGrid> density, emission_grid, temperature;
    FloatAffine density_xf, emission_xf, temperature_xf;
    // Render space to the majorant grid's [0, 16]^3, and its cells (max density).
    FloatAffine majorant_xf;
    std::vector<float> majorants;
    float background = 0;  // density outside the box, >= 0
    // Le(T) of the temperature grid at T = i * le_step kelvin; empty when nothing glows.
    std::vector<Rgb> le_table;
    float le_step = 0, temperature_scale = 1;

    Rgb GlowAt(float kelvin) const {
        if (le_table.empty() || !(kelvin > 0)) return Rgb(0.0f);
        const float x = std::min(kelvin / le_step, float(kLeTableSize - 1));
        const int i = std::min(int(x), kLeTableSize - 2);
        const float f = x - float(i);
        return le_table[size_t(i)] * (1 - f) + le_table[size_t(i) + 1] * f;
    }
};

struct SceneMedia::Impl {
    std::vector<RenderMedium> media;
};

namespace {

RenderMedium Build(const Medium& m, const Vec3d& origin) {
    RenderMedium r;
    r.type = m.type;
    r.sigma_a = m.sigma_a;
    r.sigma_s = m.sigma_s;
    r.sigma_t = m.sigma_a + m.sigma_s;
    r.emission = m.emission;
    r.g = m.g;
    r.emissive = !m.emission.IsBlack();
    if (m.type != Medium::Type::kGrid) return r;
    const float largest = r.sigma_t.MaxComponent();
    for (int c = 0; c < 3; ++c) {
        r.majorant_per_density[c] = std::max(r.sigma_t[c], kMinMajorantFraction * largest);
    }

    r.density = m.density;
    r.density_xf = RenderToIndex(*m.density, origin);
    r.background = std::max(0.0f, m.density->background);
    const auto [lo, hi] = DensityBox(*m.density);
    const Vec3d width = (hi - lo) / double(kMajorantRes);
    r.majorant_xf = RenderToIndex(*m.density, origin, lo, width);
    r.majorants = BuildMajorants(*m.density, lo, width);

    if (m.emission_grid) {
        r.emission_grid = m.emission_grid;
        r.emission_xf = RenderToIndex(*m.emission_grid, origin);
    }
    if (m.temperature) {
        float hottest = m.temperature->background;
        for (float v : m.temperature->values) hottest = std::max(hottest, v);
        const double t_max = double(hottest) * m.temperature_scale;
        if (t_max > kMinGlowK) {
            r.temperature = m.temperature;
            r.temperature_xf = RenderToIndex(*m.temperature, origin);
            r.temperature_scale = float(m.temperature_scale);
            r.le_step = float(t_max / (kLeTableSize - 1));
            r.le_table.resize(kLeTableSize);
            for (int i = 0; i < kLeTableSize; ++i) {
                const double kelvin = i == kLeTableSize - 1 ? t_max : i * double(r.le_step);
                r.le_table[size_t(i)] =
                    kelvin < kMinGlowK
                        ? Rgb(0.0f)
                        : BlackbodyRgb(kelvin) * float(BlackbodyLuminance(kelvin) / 683);
            }
            r.emissive = true;
        }
    }
    return r;
}

}  // namespace

SceneMedia::SceneMedia(const Scene& scene, const Vec3d& origin) : impl_(std::make_unique<Impl>()) {
    impl_->media.reserve(scene.media.size());
    for (const Medium& m : scene.media) impl_->media.push_back(Build(m, origin));
}

SceneMedia::~SceneMedia() = default;
SceneMedia::SceneMedia(SceneMedia&&) noexcept = default;

bool SceneMedia::empty() const { return impl_->media.empty(); }
float SceneMedia::g(int medium) const { return impl_->media[size_t(medium)].g; }
bool SceneMedia::IsEmissive(int medium) const { return impl_->media[size_t(medium)].emissive; }

bool SceneMedia::IsHomogeneousAbsorber(int medium) const {
    const RenderMedium& m = impl_->media[size_t(medium)];
    return m.type == Medium::Type::kHomogeneous && m.sigma_s.IsBlack() && !m.emissive;
}

Rgb SceneMedia::HomogeneousTransmittance(int medium, float distance) const {
    return Attenuation(impl_->media[size_t(medium)].sigma_t, distance);
}

MediumPoint SceneMedia::PointAt(int medium, const Vec3& p) const {
    const RenderMedium& m = impl_->media[size_t(medium)];
    if (m.type == Medium::Type::kHomogeneous) return {m.sigma_a, m.sigma_s, m.emission};
    const float density = std::max(0.0f, GridValue(*m.density, m.density_xf, p));
    MediumPoint mp{m.sigma_a * density, m.sigma_s * density, Rgb(0.0f)};
    if (m.emissive) {
        mp.Le = m.emission_grid
                    ? m.emission * std::max(0.0f, GridValue(*m.emission_grid, m.emission_xf, p))
                    : m.emission;
        if (m.temperature) {
            mp.Le += m.GlowAt(GridValue(*m.temperature, m.temperature_xf, p) * m.temperature_scale);
        }
    }
    return mp;
}

SceneMedia::MajorantIterator SceneMedia::Majorants(int medium, const Ray& ray, float t_max) const {
    const RenderMedium& m = impl_->media[size_t(medium)];
    MajorantIterator it;
    it.t_enter_ = it.t_exit_ = it.t_end_ = t_max;
    if (m.type == Medium::Type::kHomogeneous) {
        it.sigma_outside_ = m.sigma_t;
        return it;
    }
    it.sigma_outside_ = m.majorant_per_density * m.background;
    it.sigma_t_ = m.majorant_per_density;
    // The ray against the majorant grid's box [0, 16]^3 (slabs).
    const Vec3 o = m.majorant_xf.Apply(ray.o), d = m.majorant_xf.ApplyLinear(ray.d);
    float t0 = 0, t1 = t_max;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0) {
            if (!(o[a] >= 0 && o[a] <= kMajorantRes)) return it;
            continue;
        }
        float near = -o[a] / d[a], far = (kMajorantRes - o[a]) / d[a];
        if (near > far) std::swap(near, far);
        t0 = std::max(t0, near);
        t1 = std::min(t1, far);
    }
    if (!(t0 < t1)) return it;
    it.t_enter_ = t0;
    it.t_exit_ = t1;
    it.t_ = t0;
    it.cells_ = m.majorants.data();
    const Vec3 start = o + d * t0;
    for (int a = 0; a < 3; ++a) {
        it.voxel_[a] = std::clamp(int(start[a]), 0, kMajorantRes - 1);
        if (d[a] == 0) {
            it.next_crossing_[a] = kInfinity;
        } else if (d[a] > 0) {
            it.step_[a] = 1;
            it.voxel_limit_[a] = kMajorantRes;
            it.delta_t_[a] = 1 / d[a];
            it.next_crossing_[a] = t0 + (float(it.voxel_[a] + 1) - start[a]) / d[a];
        } else {
            it.step_[a] = -1;
            it.voxel_limit_[a] = -1;
            it.delta_t_[a] = -1 / d[a];
            it.next_crossing_[a] = t0 + (float(it.voxel_[a]) - start[a]) / d[a];
        }
    }
    return it;
}

bool SceneMedia::MajorantIterator::Next(MajorantSegment& segment) {
    for (;;) {
        switch (stage_) {
            case Stage::kBefore:
                stage_ = cells_ ? Stage::kInside : Stage::kDone;
                if (t_enter_ > 0 && !sigma_outside_.IsBlack()) {
                    segment = {0, t_enter_, sigma_outside_};
                    return true;
                }
                break;
            case Stage::kInside: {
                if (!(t_ < t_exit_)) {
                    stage_ = Stage::kAfter;
                    break;
                }
                const int axis = next_crossing_[0] < next_crossing_[1]
                                     ? (next_crossing_[0] < next_crossing_[2] ? 0 : 2)
                                     : (next_crossing_[1] < next_crossing_[2] ? 1 : 2);
                const float t1 = std::min(t_exit_, next_crossing_[axis]);
                const float density =
                    cells_[(size_t(voxel_[2]) * kMajorantRes + size_t(voxel_[1])) * kMajorantRes +
                           size_t(voxel_[0])];
                segment = {t_, t1, sigma_t_ * density};
                t_ = t1;
                voxel_[axis] += step_[axis];
                next_crossing_[axis] += delta_t_[axis];
                // Leaving the grid ends the box, also where rounding leaves a sliver before t_exit.
                if (voxel_[axis] == voxel_limit_[axis]) t_ = t_exit_;
                if (density > 0 && segment.t1 > segment.t0) return true;
                break;
            }
            case Stage::kAfter:
                stage_ = Stage::kDone;
                if (t_end_ > t_exit_ && !sigma_outside_.IsBlack()) {
                    segment = {t_exit_, t_end_, sigma_outside_};
                    return true;
                }
                break;
            case Stage::kDone:
                return false;
        }
    }
}

}  // namespace lf
