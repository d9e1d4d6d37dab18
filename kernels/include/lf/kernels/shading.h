// The surface interaction at a hit: where the BSDF is evaluated (the shading frame from
// interpolated vertex normals and normal maps), what it is made of there (the material's
// factors times its textures), and where rays leaving it start (Hanika's shadow-terminator
// offset on smooth meshes). The geometric normal stays in SurfaceHit::n: it decides sides.
#pragma once

#include <array>

#include "lf/core/scene.h"
#include "lf/core/texture.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/embree_scene.h"

namespace lf {

// A point's uvs in each set a texture may read (TextureRef::tex_coord): TEXCOORD_0, TEXCOORD_1.
using TexCoords = std::array<Vec2, 2>;

struct Shading {
    SurfacePoint point;  // the hit: p, its error bound, the geometric normal n
    // Unit shading normal on the geometric normal's side; equals point.n on flat geometry.
    // Bent, where needed, so that wo mirrored about it stays above the surface
    // (ValidReflectionNormal), which also keeps wo on its side.
    Vec3 ns;
    TexCoords uv;
    SurfaceParams params;
    Rgb emission;  // radiance leaving the front (both, if two-sided): factor times texture
    // Hanika's P' (Ray Tracing Gems II, ch. 4): the hit lifted towards the smooth surface the
    // vertex normals describe; where rays leaving on the normals' side start.
    Vec3 p_outer;

    // The triangle's vertices (render space) on smooth meshes, for ClearsFacet.
    Vec3 v[3];

    // Where a ray leaving in direction w starts from: p_outer for reflection the shading normal
    // allows just below the facet (see ClearsFacet), else the hit.
    SurfacePoint Leaving(const Vec3& w) const;
    // For w just below the facet's plane on the front (cos with n < 0) near a smooth mesh's
    // terminator, where the shading normal says it is still above the surface: true when the
    // ray from p_outer passes outside this triangle, so it does not go through the surface.
    bool ClearsFacet(const Vec3& w) const;
    // Whether light may scatter between wo and wi (world space, away from the surface; length
    // irrelevant), which the BSDF in the shading frame calls a reflection or not (`reflect`).
    // The geometric normal decides sides: a direction the two put on different sides carries
    // nothing, as that is where shading normals would leak light; the one exception is
    // reflection just below a smooth mesh's facet near the terminator that clears it.
    bool SidesAgree(const Vec3& wo, const Vec3& wi, bool reflect) const;
};

// The shading normal ns (unit, interpolated or normal-mapped) adjusted so that wo mirrored
// about it stays above the geometric surface (n, either side; wo unit, away from the surface),
// as Cycles' ensure_valid_reflection does: a bent normal must not make a reflection vanish.
// Where the mirror direction falls below min(0.01, 0.9 wo.n) the normal becomes the half vector
// of wo and that direction raised to it, keeping its azimuth; else ns unchanged.
Vec3 ValidReflectionNormal(const Vec3& ns, const Vec3& n, const Vec3& wo);

// The interaction at `hit` seen from direction wo (unit, away from the surface).
Shading Shade(const EmbreeScene& scene, const SurfaceHit& hit, const Vec3& wo);

// The radiance a light sample on an emitter carries: `radiance` (the material's emission
// factor, as LightSampler gives it) times the emission texture at the sample (and the vertex
// colour, Material::emission_by_vertex_color); black in an
// alpha-mask hole, which emits nothing because rays pass through it, and times the opacity on a
// blended surface (what rays that stop there see, on average).
Rgb EmissionAt(const EmbreeScene& scene, const SurfacePoint& light_point, const Rgb& radiance);

// Both uv sets of a triangle's point; (0, 0) for a set the mesh lacks.
TexCoords TriangleUvs(const TriangleMesh& mesh, int primitive, float b1, float b2);

// COLOR_0 of a triangle's point; white and opaque on meshes without vertex colours.
Rgba VertexColor(const TriangleMesh& mesh, int primitive, float b1, float b2);

// The material's opacity at uv: its factor times the base colour texture's alpha times the
// vertex colour's alpha there.
float Opacity(const Scene& scene, const Material& material, const TexCoords& uv,
              float vertex_alpha = 1);

// True when rays pass through the material at uv (an alpha-mask hole).
bool IsCutOut(const Scene& scene, const Material& material, const TexCoords& uv,
              float vertex_alpha = 1);

// Whether a ray passes through the material at uv, u uniform in [0, 1): through an alpha-mask
// hole always, through a blended surface when u >= its opacity.
bool PassesThrough(const Scene& scene, const Material& material, const TexCoords& uv,
                   float vertex_alpha, float u);

// A uniform number in [0, 1) for the candidate hit of a ray (origin, direction) on primitive
// `primitive` of geometry `geometry`: the blend test's, so a ray and its retraces agree, while
// rays of different samples (other origins or directions) draw independently (pbrt-v4's
// stochastic alpha test does the same).
float AlphaHash(const Vec3& origin, const Vec3& direction, unsigned geometry, unsigned primitive);

// Materials whose back faces let light out: single-sided culling spares them.
bool Transmits(const Material& material);

// Emission leaves the back face too: two-sided emitters whose back faces rays can reach (a
// single-sided mesh's back is invisible, so neither hits nor light samples see it glow).
bool EmitsFromBack(const Material& material);

}  // namespace lf
