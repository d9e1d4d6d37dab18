#include "lf/kernels/photon_map.h"

#include <cmath>
#include <utility>

#include "lf/core/sampler.h"

namespace lf {

PhotonMap::PhotonMap(std::vector<Photon> photons, float radius)
    : radius_(radius), inv_cell_(1 / radius) {
    // Two buckets per photon keeps the chains short; at least one bucket for an empty map.
    const size_t buckets = std::max<size_t>(1, 2 * photons.size());
    bucket_start_.assign(buckets + 1, 0);
    std::vector<uint32_t> bucket_of(photons.size());
    for (size_t i = 0; i < photons.size(); ++i) {
        bucket_of[i] = Bucket(Cell(photons[i].p));
        ++bucket_start_[bucket_of[i] + 1];
    }
    for (size_t b = 0; b < buckets; ++b) bucket_start_[b + 1] += bucket_start_[b];
    // Counting sort, stable: within a bucket the photons keep their tracing order.
    std::vector<uint32_t> next(bucket_start_.begin(), bucket_start_.end() - 1);
    photons_.resize(photons.size());
    for (size_t i = 0; i < photons.size(); ++i) photons_[next[bucket_of[i]]++] = photons[i];
}

std::array<int64_t, 3> PhotonMap::Cell(const Vec3& p) const {
    return {int64_t(std::floor(p.x * inv_cell_)), int64_t(std::floor(p.y * inv_cell_)),
            int64_t(std::floor(p.z * inv_cell_))};
}

uint32_t PhotonMap::Bucket(const std::array<int64_t, 3>& cell) const {
    const uint64_t h = MixBits(uint64_t(cell[0]) * 73856093ULL ^ uint64_t(cell[1]) * 19349663ULL ^
                               uint64_t(cell[2]) * 83492791ULL);
    return uint32_t(h % (bucket_start_.size() - 1));
}

}  // namespace lf
