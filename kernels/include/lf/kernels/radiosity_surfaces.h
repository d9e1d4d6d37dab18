// What radiosity takes from a scene's materials: the Lambertian reflectance and the emission of
// every patch side, and of every point for the display.
//
// A material's diffuse part is what the solve keeps (docs/radiosity.md, Scenes from modelling
// tools): lambert's albedo, the principled base's hemispherical diffuse albedo (the energy the
// path tracer's diffuse lobe carries, PrincipledBsdf::DiffuseAlbedo), black for mirrors, glass
// and glossy metal. Textures and vertex colours are averaged over each patch for the solve, by
// the sub-triangle centroids of an n x n grid, n from the patch's footprint in texels (a box
// filter over it, at most 16 x 16 samples); the display multiplies the patch's irradiance by
// the albedo at the pixel, so textures keep their detail.
#pragma once

#include <vector>

#include "lf/core/patch_mesh.h"
#include "lf/core/rgb.h"
#include "lf/kernels/embree_scene.h"

namespace lf {

struct SurfaceParams;

// Per side of a mesh: the Lambertian reflectance and the emitted exitance pi Le (0 on a side
// that does not emit), each averaged over the patch.
struct RadiositySides {
    std::vector<Rgb> reflectance, exitance;
};

class RadiositySurfaces {
  public:
    // `scene` must outlive this.
    explicit RadiositySurfaces(const EmbreeScene& scene);

    RadiositySides Sides(const PatchMesh& mesh) const;

    // Whether reflectance or emission vary over `mesh` (textures, vertex colours): only then
    // does the display need the values at its pixels.
    bool Varies(int mesh) const { return varies_[size_t(mesh)]; }

    // The reflectance of `mesh`'s material without its textures and vertex colours: the
    // largest any of its points has.
    Rgb UntexturedReflectance(int mesh) const;

    struct Point {
        Rgb reflectance;
        Rgb emission;  // radiance leaving the front face (both faces if two-sided)
    };
    Point At(int mesh, int primitive, float b1, float b2) const;

  private:
    // The diffuse reflectance for shading parameters at a point of `mesh`.
    Rgb Reflectance(int mesh, const SurfaceParams& params) const;

    const EmbreeScene& scene_;
    std::vector<bool> varies_;       // per mesh
    std::vector<bool> params_vary_;  // per mesh: textures beyond base colour and emission
    std::vector<Rgb> white_albedo_;  // per material: the reflectance of a white base
};

}  // namespace lf
