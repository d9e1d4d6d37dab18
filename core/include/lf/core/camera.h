// Pinhole, thin-lens or orthographic camera exactly as docs/scene-format.md defines it, with its
// pixel filter.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "lf/core/pixel_filter.h"
#include "lf/core/ray.h"
#include "lf/core/scene.h"

namespace lf {

// One line for the render log, e.g. "perspective from (0, 1, 5) towards (0, 1, 0), up (0, 1, 0),
// vertical field of view 40 degrees": what `--camera auto` chose, to set up the same view
// elsewhere (tools/khronos_vs_cycles.sh does in Blender). Positions to 6 significant digits.
std::string DescribeCamera(const CameraSpec& spec);

class Camera {
  public:
    // `origin` is subtracted from world positions: kernels render in a frame centred on the
    // scene so float precision is spent where the geometry is (see EmbreeScene).
    // A moving camera (motion blur) gives `motion`: where it is at evenly spaced times over the
    // shutter, the first at its opening (time 0), the last at its closing (time 1), as
    // EmbreeScene::camera_motion() holds them; at time t it is between the two nearest, its
    // position linear and its orientation slerped. Lens, film and filter are `spec`'s. Empty:
    // the camera stands still at `spec`.
    Camera(const CameraSpec& spec, const Vec3d& origin, std::span<const CameraSpec> motion = {});

    // Ray through film point (px + u, py + v); px counts from the left, py from the top. With a
    // lens, `lens` (uniform in [0, 1)^2) picks the point on the aperture it leaves from. The ray
    // leaves at `time` in the shutter (Ray::time) from where the camera is then.
    Ray GenerateRay(int px, int py, float u, float v, const Vec2& lens = {}, float time = 0) const;

    // Whether the camera moves during the shutter.
    bool Moves() const { return !motion_.empty(); }

    // Where in its pixel a sample with film numbers u (uniform in [0, 1)^2) lands, for
    // GenerateRay: distributed like the camera's pixel filter (FilterSampler); u itself for the
    // box filter.
    Vec2 SampleFilm(const Vec2& u) const { return filter_.Sample(u); }

    // Whether rays need a lens sample: a pinhole takes none, so its renders keep their bits.
    bool HasLens() const { return lens_radius_ > 0; }

    // Orthographic cameras see along one direction only: no light path reaches them by
    // chance, so the importance functions below are for perspective cameras (methods that
    // connect light paths to the camera refuse orthographic ones).
    bool IsOrthographic() const { return orthographic_; }

    // Importance: the camera's end of a light path (pbrt-v4's PerspectiveCamera::We, PDF_We,
    // SampleWi), normalised as pbrt does: We cos integrated over the film's directions and the
    // lens's area (a pinhole counts as area 1) is 1. A pixel's measurement is width * height *
    // We over the rays whose film point falls in that pixel (box filter: every film point of a
    // pixel counts alike, as SampleFilm places camera rays). A light tracer therefore adds each
    // contribution at its raster position and scales the image by width * height / (light
    // paths). Other filters: a contribution at raster position r goes to every pixel (x, y)
    // whose filter support holds it, weighted by the filter normalised to integrate to 1,
    // f(r - (x + 0.5, y + 0.5)) / integral of f, instead of to the one pixel holding r.

    // The importance of a ray leaving the lens (ray.o on it, ray.d unit), and where its film
    // point falls in raster coordinates (x from the left, y from the top, in pixels, as
    // GenerateRay's px + u, py + v) when raster is given. 0 for rays off the film.
    float We(const Ray& ray, Vec2* raster = nullptr) const;

    // The densities with which GenerateRay's rays (film point uniform over the film, lens point
    // uniform over the lens) leave the camera: pos per area of lens (1 for a pinhole), dir per
    // solid angle. Both 0 for rays off the film.
    struct ImportancePdf {
        float pos = 0, dir = 0;
    };
    ImportancePdf PdfWe(const Ray& ray) const;

    // Connects `ref` (render space) to the camera: a point on the lens for u_lens (the same map
    // GenerateRay uses, so GenerateRay with that lens sample and the returned raster position
    // gives the ray through ref), the unit direction from ref to it, the density of that lens
    // point per solid angle at ref (pinhole: distance^2 / cos, as pbrt's lens area of 1), and
    // the importance We of the ray from the lens point to ref. nullopt when ref is behind the
    // camera or off the film.
    struct ImportanceSample {
        Vec2 raster;  // x from the left, y from the top, in pixels
        Vec3 lens_point;
        Vec3 wi;  // unit, from ref towards lens_point
        float distance = 0;
        float pdf = 0;
        float we = 0;
    };
    std::optional<ImportanceSample> SampleWi(const Vec3& ref, const Vec2& u_lens = {},
                                             float time = 0) const;

    int width() const { return width_; }
    int height() const { return height_; }
    // The pixel filter the camera was made with (methods that splat check it).
    const PixelFilter& filter() const { return filter_spec_; }

  private:
    // Where the camera is and which way it looks (render space, unit axes).
    struct Pose {
        Vec3 position, forward, right, up;
    };
    // A step of a moving camera: its position and its orientation as a unit quaternion
    // (x, y, z, w) of the rotation taking (right, up, -forward) to the axes.
    struct MotionKey {
        Vec3d position;
        std::array<double, 4> rotation;
    };
    Pose PoseAt(float time) const;

    // Where ray's film point falls (raster coordinates) and the cosine of ray.d with the view
    // axis; nullopt when behind the camera or off the film.
    std::optional<Vec2> Raster(const Ray& ray, const Pose& pose, float* cos_theta) const;

    Pose pose_;                      // the still camera's
    std::vector<MotionKey> motion_;  // a moving camera's steps; empty: still
    bool orthographic_ = false;
    float tan_half_fov_ = 0, aspect_ = 1;  // tan_half_fov_: the film's half height at distance 1
                                           // (orthographic: the film's half height)
    float lens_radius_ = 0, focus_distance_ = 1;
    float film_area_ = 1;  // of the film at distance 1 from the pinhole
    float lens_area_ = 1;  // pi r^2, or 1 for a pinhole
    int width_ = 0, height_ = 0;
    PixelFilter filter_spec_;
    FilterSampler filter_;
};

}  // namespace lf
