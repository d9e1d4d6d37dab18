#include "lf/kernels/environment_emitter.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "lf/core/texture.h"

namespace lf {

namespace {
constexpr float kPi = std::numbers::pi_v<float>;

bool HasMap(const EnvironmentLight& light) {
    return light.map && light.map->width > 0 && light.map->height > 0;
}
}  // namespace

EnvironmentEmitter::EnvironmentEmitter(const EnvironmentLight& light)
    : light_(light),
      cos_rotation_(float(std::cos(light.rotate_y))),
      sin_rotation_(float(std::sin(light.rotate_y))),
      mean_(EmittableRadiance(light.radiance)) {
    if (!HasMap(light_)) return;
    const TextureImage& map = *light_.map;
    const int w = map.width, h = map.height;
    // Each texel's share of the sphere is proportional to sin(theta) at its row: sampling by
    // luminance times that puts samples where the light comes from, not where the map is dense.
    std::vector<float> weights(size_t(w) * size_t(h));
    double sum[3] = {};
    for (int y = 0; y < h; ++y) {
        const float sin_theta = std::sin(kPi * (float(y) + 0.5f) / float(h));
        for (int x = 0; x < w; ++x) {
            const Rgb le = MapValue({(float(x) + 0.5f) / float(w), (float(y) + 0.5f) / float(h)});
            weights[size_t(y) * size_t(w) + size_t(x)] = le.Luminance() * sin_theta;
            for (int c = 0; c < 3; ++c) sum[c] += double(le[c]) * sin_theta;
        }
    }
    distribution_.emplace(weights, w, h);
    // Texel solid angle (2 pi / w) (pi / h) sin(theta), over the sphere's 4 pi.
    const double scale = std::numbers::pi / (2.0 * w * h);
    mean_ = Rgb(float(sum[0] * scale), float(sum[1] * scale), float(sum[2] * scale));
}

Rgb EnvironmentEmitter::MapValue(const Vec2& uv) const {
    if (!HasMap(light_)) return EmittableRadiance(light_.radiance);
    const TextureImage& map = *light_.map;
    const int x = std::clamp(int(uv.x * float(map.width)), 0, map.width - 1);
    const int y = std::clamp(int(uv.y * float(map.height)), 0, map.height - 1);
    // 8- and 16-bit maps are sRGB-encoded colour; Texel leaves HDR texels alone.
    return EmittableRadiance(Texel(map, x, y, /*srgb=*/true).rgb * light_.radiance);
}

Vec2 EnvironmentEmitter::MapUv(const Vec3& w) const {
    // Read along w turned by +rotate_y about +y (right-handed), as Blender's Mapping node (Point)
    // turns the direction its Environment Texture reads; u = 0.5 looks along +x as in Blender.
    const float x = cos_rotation_ * w.x + sin_rotation_ * w.z;
    const float z = -sin_rotation_ * w.x + cos_rotation_ * w.z;
    const float u = 0.5f + std::atan2(z, x) / (2 * kPi);
    const float v = std::acos(std::clamp(w.y, -1.0f, 1.0f)) / kPi;
    return {std::clamp(u, 0.0f, 1.0f), std::clamp(v, 0.0f, 1.0f)};
}

Rgb EnvironmentEmitter::Le(const Vec3& w) const {
    if (!distribution_) return mean_;
    return MapValue(MapUv(w));
}

std::optional<EnvironmentEmitter::DirectionSample> EnvironmentEmitter::Sample(const Vec2& u) const {
    if (!distribution_) {
        const float z = 1 - 2 * u.x;
        const float r = std::sqrt(std::max(0.0f, 1 - z * z));
        const float phi = 2 * kPi * u.y;
        return DirectionSample{Vec3(r * std::cos(phi), r * std::sin(phi), z), mean_, 1 / (4 * kPi)};
    }
    float map_pdf = 0;
    const Vec2 uv = distribution_->Sample(u, &map_pdf);
    if (!(map_pdf > 0)) return std::nullopt;
    const float theta = uv.y * kPi, phi = 2 * kPi * (uv.x - 0.5f);
    const float sin_theta = std::sin(theta);
    if (!(sin_theta > 0)) return std::nullopt;
    // The inverse of MapUv: u = 0.5 + atan2(z, x) / (2 pi), v = acos(y) / pi, then turned back
    // by -rotate_y.
    const float x = sin_theta * std::cos(phi), y = std::cos(theta), z = sin_theta * std::sin(phi);
    const Vec3 wi(cos_rotation_ * x - sin_rotation_ * z, y, sin_rotation_ * x + cos_rotation_ * z);
    return DirectionSample{wi, MapValue(uv), map_pdf / (2 * kPi * kPi * sin_theta)};
}

float EnvironmentEmitter::Pdf(const Vec3& w) const {
    if (!distribution_) return 1 / (4 * kPi);
    const Vec2 uv = MapUv(w);
    const float sin_theta = std::sin(uv.y * kPi);
    if (!(sin_theta > 0)) return 0;
    return distribution_->Pdf(uv) / (2 * kPi * kPi * sin_theta);
}

}  // namespace lf
