#include "lf/kernels/shading.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "lf/core/sampler.h"
#include "lf/core/texture.h"
#include "lf/kernels/float_util.h"

namespace lf {
namespace {

Rgba Sample(const Scene& scene, const TextureRef& ref, const TexCoords& uv) {
    return Lookup(*scene.textures[size_t(ref.image)], ref, uv[size_t(ref.tex_coord)]);
}

// The tangent and the bitangent's sign (glTF: bitangent = sign * cross(normal, tangent)) at the
// hit: the mesh's tangents (from its file, or lf::ComputeTangents when the scene loaded)
// interpolated; false for a mesh without them.
bool TangentAt(const EmbreeScene& es, const TriangleMesh& mesh, const SurfaceHit& hit,
               Vec3* tangent, float* sign) {
    if (mesh.tangents.empty()) return false;
    const auto& tri = mesh.triangles[size_t(hit.primitive)];
    const float b[3] = {1 - hit.b1 - hit.b2, hit.b1, hit.b2};
    Vec3 t;
    float w = 0;
    for (int i = 0; i < 3; ++i) {
        const std::array<float, 4> ti = es.Tangent(hit.mesh, tri[size_t(i)], hit.time);
        t += Vec3(ti[0], ti[1], ti[2]) * b[i];
        w += ti[3] * b[i];
    }
    *tangent = t;
    *sign = w < 0 ? -1.0f : 1.0f;
    return true;
}

// The normal map's normal at the hit, or `n` where the map cannot apply (no uvs or tangent,
// or a texel that points below the geometric surface).
Vec3 NormalMapped(const EmbreeScene& es, const TextureRef& map, float scale, const SurfaceHit& hit,
                  const TexCoords& uv, const Vec3& n) {
    if (hit.mesh < 0) return n;
    const TriangleMesh& mesh = es.scene().meshes[size_t(hit.mesh)];
    if (mesh.Uvs(map.tex_coord).empty()) return n;
    Vec3 t;
    float sign;
    if (!TangentAt(es, mesh, hit, &t, &sign)) return n;
    t = t - n * Dot(n, t);  // Gram-Schmidt against the shading normal
    if (!(LengthSquared(t) > 0)) return n;
    t = Normalize(t);
    const Vec3 b = Cross(n, t) * sign;
    // Texels hold (n + 1) / 2 as linear data; the scale applies to x and y (glTF).
    const Rgb c = Sample(es.scene(), map, uv).rgb;
    const float x = (2 * c.r - 1) * scale, y = (2 * c.g - 1) * scale;
    const float z = 2 * c.b - 1;
    const Vec3 mapped = t * x + b * y + n * z;
    if (!(LengthSquared(mapped) > 0) || !(Dot(mapped, hit.n) > 0)) return n;
    return Normalize(mapped);
}

}  // namespace

namespace {

// ValidReflectionNormal on wo's side of the surface: the result may face wo's side.
Vec3 ValidReflectionNormalTowardsView(const Vec3& ns, const Vec3& n, const Vec3& wo) {
    const Vec3 ng = Dot(wo, n) < 0 ? -n : n;  // the geometric normal on wo's side
    const float cos_o = Dot(wo, ng);
    // How far above the surface the mirror direction must stay: a little, and never above wo.
    const float lift = std::min(0.9f * cos_o, 0.01f);
    const Vec3 r = ns * (2 * Dot(wo, ns)) - wo;
    const float cos_r = Dot(r, ng);
    if (cos_r >= lift) return ns;
    // Keep the mirror direction's azimuth about ng, raise it to `lift`: r' = lift ng + sin t,
    // and the normal that mirrors wo into r' is their half vector.
    Vec3 t = r - ng * cos_r;
    if (!(LengthSquared(t) > 1e-12f)) t = ng * cos_o - wo;  // r straight down: away from wo
    if (!(LengthSquared(t) > 1e-12f)) t = ns - ng * Dot(ns, ng);
    if (!(LengthSquared(t) > 1e-12f)) return ng;
    const Vec3 r_valid = ng * lift + Normalize(t) * std::sqrt(1 - lift * lift);
    const Vec3 h = wo + r_valid;
    return LengthSquared(h) > 0 ? Normalize(h) : ng;
}

}  // namespace

Vec3 ValidReflectionNormal(const Vec3& ns, const Vec3& n, const Vec3& wo) {
    // Mirroring about -h is mirroring about h: the normal keeps ns's side of the surface, which
    // tells a solid's inside from its outside (a view from inside got an outward-facing normal).
    const Vec3 valid = ValidReflectionNormalTowardsView(ns, n, wo);
    return Dot(valid, n) * Dot(ns, n) < 0 ? -valid : valid;
}

SurfacePoint Shading::Leaving(const Vec3& w) const {
    // Only rays that dip below the facet need P'. Above it the flat facet is the better origin:
    // on a convex mesh nothing can shadow it there, while P' lies outside the mesh, where
    // neighbouring facets turning away from the light would (an 8x4 sphere lost 11% of its
    // lit radiance that way).
    if (!(Dot(w, ns) > 0) || !(Dot(w, point.n) < 0) || p_outer == point.p) return point;
    // P' is P plus a vector with a non-negative component along n; only the final sum rounds.
    SurfacePoint outer = point;
    outer.p = p_outer;
    outer.p_error = point.p_error + Abs(p_outer) * Gamma(2);
    return outer;
}

bool Shading::SidesAgree(const Vec3& wo, const Vec3& wi, bool reflect) const {
    const float cos_o = Dot(wo, point.n), cos_i = Dot(wi, point.n);
    if (cos_i == 0) return false;
    if ((cos_i * cos_o > 0) == reflect) return true;
    return reflect && cos_o > 0 && ClearsFacet(wi);
}

bool Shading::ClearsFacet(const Vec3& w) const {
    const float lift = Dot(p_outer - point.p, point.n), cos_w = Dot(w, point.n);
    if (!(lift > 0) || !(cos_w < 0)) return false;
    // Where the ray meets the facet's plane; inside all three edges (counter-clockwise about n)
    // means inside the triangle.
    const Vec3 q = p_outer + w * (lift / -cos_w);
    for (int i = 0; i < 3; ++i) {
        const Vec3& a = v[i];
        const Vec3& b = v[(i + 1) % 3];
        if (Dot(Cross(b - a, q - a), point.n) < 0) return true;
    }
    return false;
}

TexCoords TriangleUvs(const TriangleMesh& mesh, int primitive, float b1, float b2) {
    TexCoords out{};
    const auto& tri = mesh.triangles[size_t(primitive)];
    const float b0 = 1 - b1 - b2;
    for (int set = 0; set < 2; ++set) {
        const std::vector<Vec2>& uvs = mesh.Uvs(set);
        if (uvs.empty()) continue;
        const Vec2 uv0 = uvs[tri[0]], uv1 = uvs[tri[1]], uv2 = uvs[tri[2]];
        out[size_t(set)] = {b0 * uv0.x + b1 * uv1.x + b2 * uv2.x,
                            b0 * uv0.y + b1 * uv1.y + b2 * uv2.y};
    }
    return out;
}

Rgba VertexColor(const TriangleMesh& mesh, int primitive, float b1, float b2) {
    if (mesh.colors.empty()) return {Rgb(1.0f), 1};
    const auto& tri = mesh.triangles[size_t(primitive)];
    const float b[3] = {1 - b1 - b2, b1, b2};
    float sum[4] = {0, 0, 0, 0};
    for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < 4; ++c) sum[c] += b[i] * mesh.colors[tri[size_t(i)]][size_t(c)];
    }
    return {Rgb(sum[0], sum[1], sum[2]), sum[3]};
}

float Opacity(const Scene& scene, const Material& material, const TexCoords& uv,
              float vertex_alpha) {
    float a = material.opacity * vertex_alpha;
    if (material.base_color_texture.valid()) a *= Sample(scene, material.base_color_texture, uv).a;
    return a;
}

bool IsCutOut(const Scene& scene, const Material& material, const TexCoords& uv,
              float vertex_alpha) {
    return material.alpha_mode == Material::AlphaMode::kMask &&
           Opacity(scene, material, uv, vertex_alpha) < material.alpha_cutoff;
}

bool PassesThrough(const Scene& scene, const Material& material, const TexCoords& uv,
                   float vertex_alpha, float u) {
    switch (material.alpha_mode) {
        case Material::AlphaMode::kOpaque:
            return false;
        case Material::AlphaMode::kMask:
            return IsCutOut(scene, material, uv, vertex_alpha);
        case Material::AlphaMode::kBlend:
            return u >= Opacity(scene, material, uv, vertex_alpha);
    }
    return false;
}

float AlphaHash(const Vec3& origin, const Vec3& direction, unsigned geometry, unsigned primitive) {
    uint64_t h = MixBits((uint64_t(geometry) << 32) | primitive);
    for (int i = 0; i < 3; ++i) {
        h = MixBits(h ^ ((uint64_t(std::bit_cast<uint32_t>(origin[i])) << 32) |
                         std::bit_cast<uint32_t>(direction[i])));
    }
    return float(h >> 40) * 0x1p-24f;
}

bool Transmits(const Material& material) {
    return material.type == Material::Type::kDielectric ||
           (material.type == Material::Type::kPrincipled && material.transmission > 0);
}

bool EmitsFromBack(const Material& material) {
    return material.two_sided_emission && material.VisibleFromBehind();
}



namespace {

// The clear coat's factor and roughness times their textures, and its own normal: its normal
// map's, or the interpolated normal where the base's is mapped, in s.ns's shading frame.
void ShadeCoat(const EmbreeScene& es, const Material& m, const SurfaceHit& hit, const Vec3& wo,
               const Vec3& interpolated, Shading& s) {
    const Scene& scene = es.scene();
    if (m.clearcoat_texture.valid()) {
        s.params.clearcoat *= Sample(scene, m.clearcoat_texture, s.uv).rgb.r;
    }
    if (m.clearcoat_roughness_texture.valid()) {
        s.params.clearcoat_roughness *= Sample(scene, m.clearcoat_roughness_texture, s.uv).rgb.g;
    }
    if (!m.clearcoat_normal_texture.valid() && !m.normal_texture.valid()) return;
    Vec3 coat = interpolated;
    if (m.clearcoat_normal_texture.valid()) {
        coat = NormalMapped(es, m.clearcoat_normal_texture, m.clearcoat_normal_scale, hit, s.uv,
                            interpolated);
    }
    coat = ValidReflectionNormal(coat, hit.n, wo);
    const Vec3 local = Frame::FromNormal(s.ns).ToLocal(coat);
    if (local.z > 0) s.params.coat_normal = local;
}

}  // namespace

Shading Shade(const EmbreeScene& es, const SurfaceHit& hit, const Vec3& wo) {
    const Scene& scene = es.scene();
    const Material& m = scene.materials[size_t(hit.material)];
    Shading s;
    Rgb vertex_color(1.0f);
    s.point = {hit.p, hit.p_error, hit.n};
    s.point.time = hit.time;
    s.ns = hit.n;
    s.p_outer = hit.p;
    if (hit.mesh >= 0) {
        const TriangleMesh& mesh = scene.meshes[size_t(hit.mesh)];
        s.uv = TriangleUvs(mesh, hit.primitive, hit.b1, hit.b2);
        vertex_color = VertexColor(mesh, hit.primitive, hit.b1, hit.b2).rgb;
        if (!mesh.normals.empty()) {
            const auto& tri = mesh.triangles[size_t(hit.primitive)];
            const float b[3] = {1 - hit.b1 - hit.b2, hit.b1, hit.b2};
            es.Triangle(hit.mesh, hit.primitive, hit.time, &s.v[0], &s.v[1], &s.v[2]);
            Vec3 n_sum, lift;
            for (int i = 0; i < 3; ++i) {
                const Vec3 ni = FaceForward(es.Normal(hit.mesh, tri[size_t(i)], hit.time), hit.n);
                n_sum += ni * b[i];
                // Hanika: project P onto each vertex's tangent plane where P lies below it.
                lift -= ni * (b[i] * std::min(0.0f, Dot(hit.p - s.v[i], ni)));
            }
            if (LengthSquared(n_sum) > 0) s.ns = Normalize(n_sum);
            s.p_outer = hit.p + lift;
        }
    }
    const Vec3 interpolated = s.ns;
    if (m.normal_texture.valid()) {
        s.ns = NormalMapped(es, m.normal_texture, m.normal_scale, hit, s.uv, s.ns);
    }
    s.ns = ValidReflectionNormal(s.ns, hit.n, wo);

    s.params = SurfaceParams::Of(m);
    s.params.base_color *= vertex_color;
    if (m.base_color_texture.valid()) {
        // An HDR or EXR colour texture can exceed 1, which no albedo may.
        const Rgb texel = Sample(scene, m.base_color_texture, s.uv).rgb;
        for (int c = 0; c < 3; ++c) s.params.base_color[c] *= std::min(texel[c], 1.0f);
    }
    if (m.metallic_roughness_texture.valid()) {
        const Rgb mr = Sample(scene, m.metallic_roughness_texture, s.uv).rgb;
        s.params.roughness *= mr.g;
        s.params.metallic *= mr.b;
    }
    if (m.specular_texture.valid()) {
        s.params.specular *= Sample(scene, m.specular_texture, s.uv).a;
    }
    if (m.specular_color_texture.valid()) {
        s.params.specular_color *= Sample(scene, m.specular_color_texture, s.uv).rgb;
    }
    if (m.clearcoat > 0) ShadeCoat(es, m, hit, wo, interpolated, s);
    if (m.sheen_color_texture.valid()) {
        s.params.sheen_color *= Sample(scene, m.sheen_color_texture, s.uv).rgb;
    }
    if (m.sheen_roughness_texture.valid()) {
        s.params.sheen_roughness *= Sample(scene, m.sheen_roughness_texture, s.uv).a;
    }
    if (m.transmission_texture.valid()) {
        s.params.transmission *= Sample(scene, m.transmission_texture, s.uv).rgb.r;
    }
    s.emission = m.emission;
    if (m.emission_by_vertex_color) s.emission *= vertex_color;
    if (m.IsEmissive() && m.emission_texture.valid()) {
        s.emission *= Sample(scene, m.emission_texture, s.uv).rgb;
    }
    return s;
}

Rgb EmissionAt(const EmbreeScene& es, const SurfacePoint& light_point, const Rgb& radiance) {
    if (light_point.mesh < 0) return radiance;
    const Scene& scene = es.scene();
    const TriangleMesh& mesh = scene.meshes[size_t(light_point.mesh)];
    const Material& m = scene.materials[size_t(mesh.material)];
    if (!m.emission_texture.valid() && m.alpha_mode == Material::AlphaMode::kOpaque &&
        !m.emission_by_vertex_color) {
        return radiance;
    }
    const TexCoords uv = TriangleUvs(mesh, light_point.primitive, light_point.b1, light_point.b2);
    const Rgba vertex = VertexColor(mesh, light_point.primitive, light_point.b1, light_point.b2);
    if (IsCutOut(scene, m, uv, vertex.a)) return Rgb(0);
    Rgb le = radiance;
    if (m.emission_by_vertex_color) le *= vertex.rgb;
    if (m.alpha_mode == Material::AlphaMode::kBlend) le *= Opacity(scene, m, uv, vertex.a);
    if (m.emission_texture.valid()) le *= Sample(scene, m.emission_texture, uv).rgb;
    return le;
}

}  // namespace lf
