// The scene's participating media in render space, for the volumetric estimators: what a medium
// holds at a point (sigma_a, sigma_s, Le) and the null-scattering walk along a ray segment
// (pbrt-v4's SampleT_maj): tentative collisions drawn against a majorant sigma_maj >= sigma_t,
// so heterogeneous grids are sampled without bias by delta tracking (a collision is real with
// probability sigma_t / sigma_maj) and their transmittance estimated by ratio tracking
// (T *= sigma_n / sigma_maj at each). A homogeneous medium's majorant is its sigma_t, every
// collision real. Grids bound their density by a coarse 16^3 majorant grid walked with a 3D DDA.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "lf/core/ray.h"
#include "lf/core/rgb.h"
#include "lf/core/sampler.h"
#include "lf/core/scene.h"

namespace lf {

// What a medium holds at a point: coefficients per metre and the emitted radiance Le (the
// source term is sigma_a Le).
struct MediumPoint {
    Rgb sigma_a, sigma_s, Le;
};

// Random numbers past a bounce's fixed sampler dimensions: the walk through a grid takes as
// many as it meets tentative collisions. A SplitMix64 stream seeded from one sampler draw, so
// the walk is deterministic per sample.
class MediumRng {
  public:
    explicit MediumRng(uint64_t seed) : state_(seed) {}
    float Uniform() {  // in [0, 1)
        state_ += 0x9e3779b97f4a7c15ULL;
        return float(MixBits(state_) >> 40) * 0x1p-24f;
    }

  private:
    uint64_t state_;
};

class SceneMedia {
  public:
    // Scene::media in render space (world minus `origin`, EmbreeScene::origin()).
    SceneMedia(const Scene& scene, const Vec3d& origin);
    ~SceneMedia();
    SceneMedia(SceneMedia&&) noexcept;

    bool empty() const;
    float g(int medium) const;
    bool IsEmissive(int medium) const;
    // Homogeneous, sigma_s = 0 and no emission: nothing happens inside but Beer's law,
    // exp(-sigma_a t), which every method evaluates without sampling (no noise).
    bool IsHomogeneousAbsorber(int medium) const;
    // Beer's law through `distance` of a homogeneous medium (IsHomogeneousAbsorber or not).
    Rgb HomogeneousTransmittance(int medium, float distance) const;

    // The tentative collisions along `ray` (render space; d need not be unit, t counts in units
    // of d) over [0, t_max) in `medium`: exponential steps against channel `hero`'s majorant
    // (0, 1 or 2), drawn from `rng`. At each collision it calls
    //   bool callback(const Vec3& p, const MediumPoint& mp, const Rgb& sigma_maj, const Rgb& t_maj)
    // with t_maj = exp(-sigma_maj s) over the distance s since the previous collision (or the
    // start); returning false stops the walk, and SampleTMaj returns Rgb(1). Otherwise it returns
    // the majorant transmittance from the last collision to t_max. Where the hero channel's
    // majorant is 0 no collision is drawn and t_maj carries the other channels' attenuation.
    template <typename Callback>
    Rgb SampleTMaj(int medium, const Ray& ray, float t_max, int hero, MediumRng& rng,
                   Callback&& callback) const;

  private:
    // A stretch [t0, t1) of a unit-direction ray over which sigma_maj bounds sigma_t.
    struct MajorantSegment {
        float t0, t1;
        Rgb sigma_maj;
    };
    // The segments along a ray, in order (pbrt-v4's DDAMajorantIterator): a homogeneous medium's
    // one segment; for a grid, its background before the density's box, the box's majorant cells
    // by a 3D DDA, its background after. Segments of majorant 0 are skipped.
    class MajorantIterator {
      public:
        bool Next(MajorantSegment& segment);

      private:
        friend class SceneMedia;
        enum class Stage { kBefore, kInside, kAfter, kDone };
        Stage stage_ = Stage::kBefore;
        float t_ = 0, t_enter_ = 0, t_exit_ = 0, t_end_ = 0;
        Rgb sigma_outside_;             // background density times sigma_t (sigma_t if homogeneous)
        Rgb sigma_t_;  // the majorant per unit density inside the box (RenderMedium)
        const float* cells_ = nullptr;  // the majorant grid, null when the box is not crossed
        int voxel_[3] = {}, step_[3] = {}, voxel_limit_[3] = {};
        float next_crossing_[3] = {}, delta_t_[3] = {};
    };

    // `ray.d` unit.
    MajorantIterator Majorants(int medium, const Ray& ray, float t_max) const;
    MediumPoint PointAt(int medium, const Vec3& p) const;
    // exp(-sigma s) per channel, 1 where sigma is 0 (also for an infinite s).
    static Rgb Attenuation(const Rgb& sigma, float s) {
        Rgb a(1.0f);
        for (int c = 0; c < 3; ++c) {
            // Nothing over no distance, even for an infinite sigma (no 0 * inf).
            if (sigma[c] != 0 && s > 0) a[c] = std::exp(-sigma[c] * s);
        }
        return a;
    }

    struct Impl;
    std::unique_ptr<Impl> impl_;
};

template <typename Callback>
Rgb SceneMedia::SampleTMaj(int medium, const Ray& ray, float t_max, int hero, MediumRng& rng,
                           Callback&& callback) const {
    // Distances in scene units, so that sigma_maj is per metre.
    const float length = Length(ray.d);
    Ray unit = ray;
    unit.d = ray.d / length;
    MajorantIterator segments = Majorants(medium, unit, t_max * length);
    Rgb t_maj(1.0f);
    MajorantSegment s;
    while (segments.Next(s)) {
        const float sigma = s.sigma_maj[hero];
        if (sigma == 0) {
            t_maj *= Attenuation(s.sigma_maj, s.t1 - s.t0);
            continue;
        }
        for (float t = s.t0;;) {
            // Exponential with rate sigma; 1 - u is in (0, 1], so the step is finite.
            const float dt = -std::log(1 - rng.Uniform()) / sigma;
            if (t + dt >= s.t1) {
                t_maj *= Attenuation(s.sigma_maj, s.t1 - t);
                break;
            }
            t += dt;
            t_maj *= Attenuation(s.sigma_maj, dt);
            const Vec3 p = unit.o + unit.d * t;
            if (!callback(p, PointAt(medium, p), s.sigma_maj, t_maj)) return Rgb(1.0f);
            t_maj = Rgb(1.0f);
        }
    }
    return t_maj;
}

}  // namespace lf
