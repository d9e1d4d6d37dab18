// The scene's participating media in render space, for the volumetric estimators: what a medium
// holds at a point (sigma_a, sigma_s, Le) and the null-scattering walk along a ray segment
// (pbrt-v4's SampleT_maj): tentative collisions drawn against a majorant sigma_maj >= sigma_t,
// so heterogeneous grids are sampled without bias by delta tracking (a collision is real with
// probability sigma_t / sigma_maj) and their transmittance estimated by ratio tracking
// (T *= sigma_n / sigma_maj at each). A homogeneous medium's majorant is its sigma_t, every
// collision real. Grids bound their density by a coarse 16^3 majorant grid walked with a 3D DDA.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "lf/core/ray.h"
#include "lf/core/rgb.h"
#include "lf/core/scene.h"
#include "lf/core/sampler.h"

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
    // sigma_s = 0 and sigma_a constant: transmittance is Beer's law, exp(-sigma_a t), which
    // every method can evaluate without sampling.
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
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace lf
