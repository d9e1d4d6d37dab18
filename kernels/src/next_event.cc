#include "lf/kernels/next_event.h"

namespace lf {

const MediumInterface& InterfaceAt(const Scene& scene, const SurfaceHit& hit) {
    return hit.mesh >= 0 ? scene.meshes[size_t(hit.mesh)].media
                         : scene.spheres[size_t(hit.sphere)].media;
}

Rgb Attenuation(const EmbreeScene& scene, int medium, float distance) {
    return medium < 0 ? Rgb(1.0f) : scene.media().HomogeneousTransmittance(medium, distance);
}

Rgb NextEventEstimate(const EmbreeScene& scene, const LightSampler& lights, const SurfaceHit& hit,
                      const Shading& sh, const Vec3& wo_world, const Bsdf& bsdf, int medium,
                      const Rgb& beta, float u_pick, const Vec2& u_light, RenderStats& stats) {
    const std::optional<LightSample> ls = lights.Sample(hit.p, sh.ns, u_pick, u_light, hit.time);
    if (!ls) return Rgb();
    const Frame frame = Frame::FromNormal(sh.ns);
    const Vec3 wo = frame.ToLocal(wo_world);
    const Vec3 wi = frame.ToLocal(ls->wi);
    const Rgb f = sh.SidesAgree(wo_world, ls->wi, wi.z * wo.z > 0)
                      ? bsdf.Eval(wo, wi) * std::abs(wi.z)
                      : Rgb();
    const Rgb radiance = f.IsBlack() ? Rgb() : EmissionAt(scene, ls->point, ls->radiance);
    if (radiance.IsBlack() || !(ls->pdf > 0)) return Rgb();
    ++stats.rays;
    if (scene.Occluded(SpawnRayTo(sh.Leaving(ls->wi), ls->point))) return Rgb();
    const float w = ls->delta ? 1.0f : PowerHeuristic(ls->pdf, bsdf.Pdf(wo, wi));
    const int through = wi.z * wo.z < 0 ? MediumAfter(scene.scene(), medium, hit, ls->wi) : medium;
    return beta * f * radiance * (w / ls->pdf) *
           Attenuation(scene, through, Length(ls->point.p - hit.p));
}

}  // namespace lf
