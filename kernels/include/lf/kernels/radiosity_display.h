// Showing a radiosity solution: a RadianceEstimator for the tile renderer, so the image is the
// same kind of EXR the path tracer writes, and a PLY export of the coloured patch mesh.
//
// A camera ray returns B/π of the patch side it hits (Lambertian radiance; B includes the
// emission, so emitters need nothing extra), or the sky and sun disks where it leaves the scene.
// Flat shading uses the patch's value; smooth shading interpolates corner values, each the
// area-weighted mean B of the sides that share the vertex, face the same way and lie within 30° of
// each other (creases stay sharp).
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "lf/core/patch_mesh.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/radiance.h"

namespace lf {

class LightSampler;
class RadiositySurfaces;

enum class RadiosityShading { kFlat, kSmooth };

// "flat", "smooth".
absl::StatusOr<RadiosityShading> ParseRadiosityShading(std::string_view name);
const char* RadiosityShadingName(RadiosityShading shading);

// Radiosity at the three corners of every side, in the patch's corner order.
std::vector<std::array<Rgb, 3>> SmoothCorners(const PatchMesh& mesh,
                                              std::span<const Rgb> radiosity);

class RadiosityDisplay : public RadianceEstimator {
  public:
    // `mesh` must outlive the display; `radiosity` and `irradiance` (all the light arriving,
    // the lights' direct irradiance included) have one value per side.
    RadiosityDisplay(const EmbreeScene& scene, const PatchMesh& mesh, std::vector<Rgb> radiosity,
                     std::vector<Rgb> irradiance, RadiosityShading shading);
    ~RadiosityDisplay() override;

    Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const override;
    const EmbreeScene& geometry() const override { return scene_; }

    // Radiance leaving one side of the point (b1, b2) of a scene triangle: B / pi, or where the
    // material is textured (or has vertex colours) albedo(uv) H / pi + Le(uv), H the side's
    // irradiance, so a texture keeps its detail. Sides without an unknown have radiosity 0.
    Rgb Radiance(int mesh, int primitive, double b1, double b2, bool back) const;
    // Irradiance (W m^-2) arriving on that side, shaded as the radiance is: the solve's per side
    // (the lights' direct irradiance plus F B), whatever the reflectance there; 0 on a side
    // without an unknown, which nothing lies in front of.
    Rgb Irradiance(int mesh, int primitive, double b1, double b2, bool back) const;
    std::span<const Rgb> irradiance() const { return irradiance_; }  // per side

  private:
    const EmbreeScene& scene_;
    const PatchMesh& mesh_;
    // The value of a side at the point: flat, or interpolated between its corners.
    Rgb Shade(std::span<const Rgb> per_side, const std::vector<std::array<Rgb, 3>>& corners,
              int mesh, int primitive, double b1, double b2, bool back) const;

    std::unique_ptr<const RadiositySurfaces> surfaces_;  // textured albedo and emission
    std::unique_ptr<const LightSampler> sky_;  // what rays that leave the scene see, if any
    std::vector<Rgb> radiosity_, irradiance_;
    // Smooth shading only.
    std::vector<std::array<Rgb, 3>> corners_, irradiance_corners_;
};

// ASCII PLY of every side with an unknown (back sides wound the other way), world positions,
// vertex colours the smooth radiance B/π sRGB-encoded and clamped to [0, 1], and `property float
// illuminance`: lux arriving on the side at the vertex as `display` (of this solution) shades it
// (smooth: the same area-weighted corner means as the colours), 4 significant digits. A vertex
// is written once per distinct colour and illuminance, so a side of a flat surface shares all
// its vertices.
absl::Status WriteRadiosityPly(const std::string& path, const PatchMesh& mesh,
                               std::span<const Rgb> radiosity, const RadiosityDisplay& display);

}  // namespace lf
