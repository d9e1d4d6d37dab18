#include "lf/kernels/whitted.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "lf/kernels/bsdf.h"
#include "lf/kernels/next_event.h"
#include "lf/kernels/shading.h"

namespace lf {

namespace {

// Has a delta lobe everywhere: a texture only scales the factors, so a smooth principled
// material's constant parameters decide it for every point.
bool IsSpecular(const Material& m) { return Bsdf(m).HasDeltaLobe(); }

// Reflects light, but not only as a delta BSDF: a vertex Whitted ends a ray tree at.
bool ReflectsDiffusely(const Material& m) {
    if (Bsdf(m).IsDelta()) return false;
    return m.type != Material::Type::kLambert || !m.reflectance.IsBlack();
}

}  // namespace

std::vector<std::string> WhittedMissingTerms(const Scene& scene) {
    const auto material = [&](int index) -> const Material& {
        return scene.materials[size_t(index)];
    };
    // The non-specular reflectors: their triangles' planes (unit normal n, offset n.p) and
    // their spheres.
    bool specular = false, one_plane = true, have_plane = false;
    Vec3d plane_n;
    double plane_d = 0;
    int diffuse_triangles = 0, diffuse_spheres = 0;
    for (const TriangleMesh& mesh : scene.meshes) {
        const Material& m = material(mesh.material);
        specular = specular || IsSpecular(m);
        if (!ReflectsDiffusely(m)) continue;
        for (const auto& t : mesh.triangles) {
            const Vec3d& a = mesh.positions[t[0]];
            const Vec3d n = Cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a);
            if (LengthSquared(n) == 0) continue;  // degenerate: not a surface
            ++diffuse_triangles;
            const Vec3d u = Normalize(n);
            if (!have_plane) {
                have_plane = true;
                plane_n = u;
                plane_d = Dot(u, a);
                continue;
            }
            // Coplanar up to orientation, to a relative 1e-9 of the offset.
            const double tolerance = 1e-9 * std::max(1.0, std::abs(plane_d));
            const bool parallel = std::abs(std::abs(Dot(u, plane_n)) - 1) < 1e-9;
            if (!parallel || std::abs(Dot(plane_n, a) - plane_d) > tolerance) one_plane = false;
        }
    }
    for (const Sphere& s : scene.spheres) {
        const Material& m = material(s.material);
        specular = specular || IsSpecular(m);
        if (ReflectsDiffusely(m)) ++diffuse_spheres;
    }
    const bool diffuse = diffuse_triangles + diffuse_spheres > 0;
    const bool sees_itself = diffuse_spheres > 1 ||
                             (diffuse_spheres == 1 && diffuse_triangles > 0) ||
                             (diffuse_triangles > 0 && !one_plane);
    std::vector<std::string> missing;
    if (sees_itself) {
        missing.push_back(
            "diffuse and glossy interreflection (L D D+ S* E: indirect light, colour bleeding, "
            "glossy reflections of lit surfaces)");
    }
    if (specular && diffuse) {
        missing.push_back(
            "caustics (L S+ D S* E: light that mirrors and glass reflect or refract onto other "
            "surfaces; shadows of glass are black)");
    }
    return missing;
}

WhittedTracer::WhittedTracer(const EmbreeScene& scene, int max_depth, LightStrategy strategy)
    : scene_(scene),
      lights_(scene, strategy),
      max_depth_(max_depth < 0 ? kWhittedUnlimitedDepth : max_depth),
      unlimited_(max_depth < 0) {
    for (size_t i = 0; i < lights_.size(); ++i) {
        if (lights_.IsDeltaLight(i)) delta_lights_.push_back(i);
    }
}

Rgb WhittedTracer::Li(const Ray& camera_ray, Sampler& sampler, RenderStats& stats) const {
    return Trace(camera_ray, 0, -1, sampler, stats);
}

Rgb WhittedTracer::Trace(const Ray& ray, int depth, int medium, Sampler& sampler,
                         RenderStats& stats) const {
    const std::vector<Material>& materials = scene_.scene().materials;
    ++stats.rays;
    const std::optional<SurfaceHit> hit = scene_.Intersect(ray);
    // Every ray here left the camera or a delta lobe: emission counts with full weight.
    if (!hit) return lights_.EscapedRadiance(Normalize(ray.d));
    Rgb beta(1);
    if (medium >= 0) {
        beta = Attenuation(scene_, medium, hit->t * Length(ray.d));
        if (beta.IsBlack()) return {};
    }
    const Material& material = materials[size_t(hit->material)];
    const Vec3& ng = hit->n;
    const float cos_o_ng = -Dot(ray.d, ng);
    const Shading sh = Shade(scene_, *hit, -ray.d);

    Rgb L;
    if ((cos_o_ng > 0 || EmitsFromBack(material)) && !sh.emission.IsBlack()) L += sh.emission;
    if (depth == max_depth_) {
        // Only a specular hit would have gone on: the cap cut its ray tree.
        if (unlimited_ && IsSpecular(material)) ++stats.truncated_paths;
        return beta * L;
    }

    // The BSDF lives in the shading frame; Shading::SidesAgree decides by the geometric normal.
    const Frame frame = Frame::FromNormal(sh.ns);
    const Vec3 wo = frame.ToLocal(-ray.d);
    const Bsdf bsdf(material, sh.params);

    // A smooth coat over a smooth base reflects by two delta lobes in one direction, which the
    // deterministic split below cannot tell apart: such a surface takes the random pick too.
    if (!bsdf.IsDelta() || sh.params.clearcoat > 0) {
        if (!bsdf.IsDelta()) {
            // Direct light only, and the ray tree ends: every delta light, as Whitted's shadow rays
            // (no noise from picking among them), plus one sample of the LightSampler for the
            // others, whose delta picks are dropped (the non-delta picks alone estimate the rest
            // without bias, each weighted by its own pick probability). No MIS: nothing else
            // reaches the lights from here.
            const auto direct = [&](const LightSample& ls) -> Rgb {
                if (!(ls.pdf > 0)) return {};
                const Vec3 wi = frame.ToLocal(ls.wi);
                const Rgb f = sh.SidesAgree(-ray.d, ls.wi, wi.z * wo.z > 0)
                                  ? bsdf.Eval(wo, wi) * std::abs(wi.z)
                                  : Rgb();
                if (f.IsBlack()) return {};
                const Rgb radiance = EmissionAt(scene_, ls.point, ls.radiance);
                if (radiance.IsBlack()) return {};
                ++stats.rays;
                if (scene_.Occluded(SpawnRayTo(sh.Leaving(ls.wi), ls.point))) return {};
                const int through =
                    wi.z * wo.z < 0 ? MediumAfter(scene_.scene(), medium, *hit, ls.wi) : medium;
                return f * radiance / ls.pdf *
                       Attenuation(scene_, through, Length(ls.point.p - hit->p));
            };
            for (const size_t i : delta_lights_) {
                if (const std::optional<LightSample> ls =
                        lights_.SampleDeltaLight(i, hit->p, hit->time)) {
                    L += direct(*ls);
                }
            }
            if (delta_lights_.size() < lights_.size()) {
                const float u_pick = sampler.Get1D();
                const Vec2 u_light = sampler.Get2D();
                const std::optional<LightSample> ls =
                    lights_.Sample(hit->p, sh.ns, u_pick, u_light, hit->time);
                if (ls && !ls->delta) L += direct(*ls);
            }
        }
        // A smooth surface over a diffuse base also reflects (or refracts) as a mirror: one of
        // its delta lobes, picked as Sample picks it, is followed with its weight over the
        // pick's probability. The draws come after the light's, and only for such surfaces,
        // so other scenes keep their sample streams.
        if (bsdf.HasDeltaLobe()) {
            const float uc = sampler.Get1D();
            const Vec2 u = sampler.Get2D();
            const std::optional<BsdfSample> bs = bsdf.Sample(wo, uc, u);
            if (bs && bs->delta && bs->pdf > 0) {
                L += Follow(ray, *hit, sh, material, wo, *bs,
                            bs->f * (std::abs(bs->wi.z) / bs->pdf), depth, medium, sampler, stats);
            }
        }
        return beta * L;
    }

    // A delta BSDF: every lobe is followed, weighted by its value times the cosine (what
    // Bsdf::Sample's f |cos| / pdf is before the division by the lobe's choice probability).
    // uc = 0 picks the reflection (when Fresnel reflects anything), uc = 1 the refraction
    // (none under total internal reflection); a mirror and a smooth metal have one lobe.
    const std::optional<BsdfSample> lobes[2] = {
        bsdf.Sample(wo, 0, Vec2()),
        Transmits(material) ? bsdf.Sample(wo, 1, Vec2()) : std::nullopt,
    };
    bool reflected = false, refracted = false;
    for (const std::optional<BsdfSample>& lobe : lobes) {
        if (!lobe || !(lobe->pdf > 0)) continue;
        const bool transmitted = lobe->wi.z * wo.z < 0;
        // With a Fresnel reflectance of 0, uc = 0 yields the refraction too: follow it once.
        bool& done = transmitted ? refracted : reflected;
        if (done) continue;
        done = true;
        L += Follow(ray, *hit, sh, material, wo, *lobe, lobe->f * std::abs(lobe->wi.z), depth,
                    medium, sampler, stats);
    }
    return beta * L;
}

Rgb WhittedTracer::Follow(const Ray& ray, const SurfaceHit& hit, const Shading& sh,
                          const Material& material, const Vec3& wo, const BsdfSample& lobe,
                          const Rgb& weight, int depth, int medium, Sampler& sampler,
                          RenderStats& stats) const {
    const Vec3 wi = Frame::FromNormal(sh.ns).FromLocal(lobe.wi);
    if (!sh.SidesAgree(-ray.d, wi, lobe.wi.z * wo.z > 0) || weight.IsBlack()) return {};
    const int next_medium =
        lobe.wi.z * wo.z < 0 ? MediumAfter(scene_.scene(), medium, hit, wi) : medium;
    return weight * Trace(SpawnRay(sh.Leaving(wi), wi), depth + 1, next_medium, sampler, stats);
}

}  // namespace lf
