// The photons of one progressive-photon-mapping pass (lf/kernels/ppm.h) and the fixed-radius
// queries its density estimates make. A spatial hash grid (Teschner et al. 2003, as in
// Hachisuka's PPM and pbrt-v4's SPPM, there over visible points): cells are cubes of side r, so
// the photons within r of a point lie in the 3 x 3 x 3 cells around the point's cell. Cells hash
// into 2 N buckets; Build sorts the photons by bucket with a counting sort, stable in photon
// index order, so the same photons give the same layout and the same summation order on any
// machine and thread count. Queries check the distance of every photon in the visited buckets,
// so hash collisions cost time, never correctness.
//
// Memory: sizeof(Photon) = 40 bytes per photon plus one 4-byte bucket offset per photon (2 N + 1
// of them for N photons): about 48 bytes per photon.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "lf/core/rgb.h"
#include "lf/core/vec.h"

namespace lf {

struct Photon {
    Vec3 p;         // render space, on a non-delta surface
    Vec3 wi;        // unit, towards where the photon came from (the BSDF's wi at p)
    Rgb power;      // flux carried, W; the pass's estimate divides by the photons emitted
    int depth = 0;  // scattering events before arriving at p (>= 1: direct light is not stored)
};

class PhotonMap {
  public:
    PhotonMap() = default;
    // Takes the photons (in their tracing order) and a query radius > 0.
    PhotonMap(std::vector<Photon> photons, float radius);

    size_t size() const { return photons_.size(); }
    float radius() const { return radius_; }
    // In bucket order (not the order Build was given).
    const std::vector<Photon>& photons() const { return photons_; }
    size_t MemoryBytes() const {
        return photons_.capacity() * sizeof(Photon) + bucket_start_.capacity() * sizeof(uint32_t);
    }

    // Calls f(photon) for every photon within the radius of p (distance <= radius), each once,
    // in a fixed order for a given p and photon set.
    template <typename F>
    void ForEachWithin(const Vec3& p, F&& f) const {
        if (photons_.empty()) return;
        const float r2 = radius_ * radius_;
        const std::array<int64_t, 3> c = Cell(p);
        // The 27 cells' buckets, each visited once even when two cells hash into one bucket.
        std::array<uint32_t, 27> buckets;
        int n = 0;
        for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const uint32_t b = Bucket({c[0] + dx, c[1] + dy, c[2] + dz});
                    bool seen = false;
                    for (int i = 0; i < n && !seen; ++i) seen = buckets[size_t(i)] == b;
                    if (!seen) buckets[size_t(n++)] = b;
                }
            }
        }
        for (int i = 0; i < n; ++i) {
            const uint32_t b = buckets[size_t(i)];
            for (uint32_t k = bucket_start_[b]; k < bucket_start_[b + 1]; ++k) {
                const Photon& photon = photons_[k];
                const Vec3 d = photon.p - p;
                if (Dot(d, d) <= r2) f(photon);
            }
        }
    }

  private:
    std::array<int64_t, 3> Cell(const Vec3& p) const;
    uint32_t Bucket(const std::array<int64_t, 3>& cell) const;

    std::vector<Photon> photons_;
    std::vector<uint32_t> bucket_start_;  // photons_[bucket_start_[b], bucket_start_[b + 1])
    float radius_ = 1, inv_cell_ = 1;
};

}  // namespace lf
