#include "lf/kernels/radiosity_surfaces.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "lf/kernels/principled_bsdf.h"
#include "lf/kernels/shading.h"

namespace lf {

namespace {

// Averaging grid per patch edge: enough for a box filter of about two texels per sample.
constexpr int kMaxSamplesPerEdge = 16;

// Textures that change the diffuse reflectance other than by scaling the base colour.
bool ParamsVary(const Material& m) {
    return m.metallic_roughness_texture.valid() || m.specular_texture.valid() ||
           m.specular_color_texture.valid() || m.transmission_texture.valid() ||
           (m.clearcoat > 0 &&
            (m.clearcoat_texture.valid() || m.clearcoat_roughness_texture.valid())) ||
           m.sheen_color_texture.valid() || m.sheen_roughness_texture.valid();
}

Rgb DiffuseReflectance(const Material& m, const SurfaceParams& params) {
    switch (m.type) {
        case Material::Type::kLambert:
            return params.base_color;
        case Material::Type::kPrincipled:
            return PrincipledBsdf(m, params).DiffuseAlbedo();
        default:
            return {};
    }
}

// The largest image among the textures the material reads, times its uv scale: texels per uv
// unit, to size the averaging grid.
double TexelsPerUv(const Scene& scene, const Material& m) {
    double most = 0;
    for (const TextureRef* ref :
         {&m.base_color_texture, &m.emission_texture, &m.metallic_roughness_texture,
          &m.specular_texture, &m.specular_color_texture, &m.transmission_texture,
          &m.sheen_color_texture}) {
        if (!ref->valid()) continue;
        const TextureImage& image = *scene.textures[size_t(ref->image)];
        const double scale = std::max(std::abs(ref->scale.x), std::abs(ref->scale.y));
        most = std::max(most, std::max(image.width, image.height) * scale);
    }
    return most;
}

SurfaceHit HitAt(const EmbreeScene& scene, int mesh, int primitive, float b1, float b2) {
    const SurfacePoint p = scene.TrianglePoint(mesh, primitive, b1, b2, 0);
    SurfaceHit hit;
    hit.p = p.p;
    hit.p_error = p.p_error;
    hit.n = p.n;
    hit.material = scene.scene().meshes[size_t(mesh)].material;
    hit.mesh = mesh;
    hit.primitive = primitive;
    hit.b1 = b1;
    hit.b2 = b2;
    return hit;
}

}  // namespace

RadiositySurfaces::RadiositySurfaces(const EmbreeScene& scene) : scene_(scene) {
    const Scene& s = scene.scene();
    for (const Material& m : s.materials) {
        SurfaceParams white = SurfaceParams::Of(m);
        white.base_color = Rgb(1.0f);
        white_albedo_.push_back(DiffuseReflectance(m, white));
    }
    for (const TriangleMesh& mesh : s.meshes) {
        const Material& m = s.materials[size_t(mesh.material)];
        params_vary_.push_back(ParamsVary(m));
        varies_.push_back(params_vary_.back() || m.base_color_texture.valid() ||
                          (m.IsEmissive() && m.emission_texture.valid()) || !mesh.colors.empty());
    }
}

Rgb RadiositySurfaces::Reflectance(int mesh, const SurfaceParams& params) const {
    const Scene& s = scene_.scene();
    const int material = s.meshes[size_t(mesh)].material;
    // The diffuse albedo is linear in the base colour: one integral per material serves every
    // texel unless other parameters vary too.
    if (params_vary_[size_t(mesh)])
        return DiffuseReflectance(s.materials[size_t(material)], params);
    Rgb base;
    for (int c = 0; c < 3; ++c) base[c] = std::clamp(params.base_color[c], 0.0f, 1.0f);
    return base * white_albedo_[size_t(material)];
}

Rgb RadiositySurfaces::UntexturedReflectance(int mesh) const {
    const Scene& s = scene_.scene();
    return Reflectance(mesh,
                       SurfaceParams::Of(s.materials[size_t(s.meshes[size_t(mesh)].material)]));
}

RadiositySurfaces::Point RadiositySurfaces::At(int mesh, int primitive, float b1, float b2) const {
    const SurfaceHit hit = HitAt(scene_, mesh, primitive, b1, b2);
    const Shading shading = Shade(scene_, hit, hit.n);
    return {Reflectance(mesh, shading.params), shading.emission};
}

RadiositySides RadiositySurfaces::Sides(const PatchMesh& mesh) const {
    const Scene& s = scene_.scene();
    const auto& patches = mesh.patches();
    std::vector<Point> per_patch(patches.size());
    tbb::parallel_for(size_t(0), patches.size(), [&](size_t p) {
        const PatchMesh::Patch& patch = patches[p];
        const TriangleMesh& tm = s.meshes[size_t(patch.mesh)];
        const Material& m = s.materials[size_t(tm.material)];
        if (!varies_[size_t(patch.mesh)]) {
            per_patch[p] = {UntexturedReflectance(patch.mesh), m.emission};
            return;
        }
        // The patch's footprint in texels: its longest uv edge.
        int n = 2;
        const double texels = TexelsPerUv(s, m);
        if (texels > 0 && !tm.uvs.empty()) {
            Vec2 uv[3];
            for (size_t c = 0; c < 3; ++c) {
                std::array<double, 3> corner{0, 0, 0};
                corner[c] = 1;
                const auto [b1, b2] = mesh.TriangleBarycentrics(int64_t(p), corner);
                uv[c] = TriangleUvs(tm, patch.primitive, float(b1), float(b2))[0];
            }
            const auto distance = [](const Vec2& a, const Vec2& b) {
                return std::hypot(double(a.x - b.x), double(a.y - b.y));
            };
            const double longest =
                std::max({distance(uv[0], uv[1]), distance(uv[1], uv[2]), distance(uv[2], uv[0])});
            n = std::clamp(int(std::ceil(longest * texels / 2)), 2, kMaxSamplesPerEdge);
        }
        Point sum;
        const std::vector<GridTriangle> cells = SubdivisionCells(n);
        for (const GridTriangle& cell : cells) {
            const double w1 = (cell[0][0] + cell[1][0] + cell[2][0]) / (3.0 * n);
            const double w2 = (cell[0][1] + cell[1][1] + cell[2][1]) / (3.0 * n);
            const auto [b1, b2] = mesh.TriangleBarycentrics(int64_t(p), {1 - w1 - w2, w1, w2});
            const Point at = At(patch.mesh, patch.primitive, float(b1), float(b2));
            sum.reflectance += at.reflectance;
            sum.emission += at.emission;
        }
        const float inv = 1.0f / float(cells.size());
        per_patch[p] = {sum.reflectance * inv, sum.emission * inv};
    });
    RadiositySides out;
    for (const PatchMesh::Side& side : mesh.sides()) {
        const PatchMesh::Patch& patch = patches[size_t(side.patch)];
        const Material& m = s.materials[size_t(s.meshes[size_t(patch.mesh)].material)];
        const Point& at = per_patch[size_t(side.patch)];
        out.reflectance.push_back(at.reflectance);
        const bool emits = !side.back || m.two_sided_emission;
        out.exitance.push_back(emits ? at.emission * float(std::numbers::pi) : Rgb());
    }
    return out;
}

}  // namespace lf
