#include "lf/kernels/aov_tracer.h"

#include "lf/kernels/fresnel.h"
#include "lf/kernels/shading.h"

namespace lf {

namespace {

Rgb Albedo(const Material& material, const SurfaceParams& params) {
    switch (material.type) {
        case Material::Type::kMirror:
        case Material::Type::kDielectric:
            return Rgb(1.0f);
        case Material::Type::kGlossy:
            return material.conductor ? FrComplex(1.0f, material.eta, material.k)
                                      : params.base_color;
        case Material::Type::kLambert:
        case Material::Type::kPrincipled:
        case Material::Type::kInterface:  // never a first hit (TraceFirstHit passes it)
            return params.base_color;
    }
    return params.base_color;
}

}  // namespace

Bsdf IrradianceBsdf() {
    Material white;
    white.type = Material::Type::kLambert;
    white.reflectance = Rgb(1);
    return Bsdf(white, SurfaceParams::Of(white));
}

std::optional<FirstHit> TraceFirstHit(const EmbreeScene& scene, const Ray& camera_ray) {
    Ray ray = camera_ray;
    float distance = 0;
    for (;;) {
        const std::optional<SurfaceHit> hit = scene.Intersect(ray);
        if (!hit) return std::nullopt;
        distance += hit->t * Length(ray.d);
        const Material& material = scene.scene().materials[size_t(hit->material)];
        if (material.type == Material::Type::kInterface) {
            // A boundary between media is not a surface: the first hit lies beyond it.
            ray = SpawnRay(HitPoint(*hit), ray.d);
            continue;
        }
        const Shading sh = Shade(scene, *hit, -ray.d);
        return FirstHit{Albedo(material, sh.params), sh.ns, distance};
    }
}

}  // namespace lf
