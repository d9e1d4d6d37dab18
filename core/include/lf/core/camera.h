// Pinhole or thin-lens camera exactly as docs/scene-format.md defines it, with its pixel filter.
#pragma once

#include "lf/core/pixel_filter.h"
#include "lf/core/ray.h"
#include "lf/core/scene.h"

namespace lf {

class Camera {
  public:
    // `origin` is subtracted from world positions: kernels render in a frame centred on the
    // scene so float precision is spent where the geometry is (see EmbreeScene).
    Camera(const CameraSpec& spec, const Vec3d& origin);

    // Ray through film point (px + u, py + v); px counts from the left, py from the top. With a
    // lens, `lens` (uniform in [0, 1)^2) picks the point on the aperture it leaves from.
    Ray GenerateRay(int px, int py, float u, float v, const Vec2& lens = {}) const;

    // Where in its pixel a sample with film numbers u (uniform in [0, 1)^2) lands, for
    // GenerateRay: distributed like the camera's pixel filter (FilterSampler); u itself for the
    // box filter.
    Vec2 SampleFilm(const Vec2& u) const { return filter_.Sample(u); }

    // Whether rays need a lens sample: a pinhole takes none, so its renders keep their bits.
    bool HasLens() const { return lens_radius_ > 0; }

    int width() const { return width_; }
    int height() const { return height_; }

  private:
    Vec3 position_, forward_, right_, up_;
    float tan_half_fov_ = 0, aspect_ = 1;
    float lens_radius_ = 0, focus_distance_ = 1;
    int width_ = 0, height_ = 0;
    FilterSampler filter_;
};

}  // namespace lf
