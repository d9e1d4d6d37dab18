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
            return params.base_color;
    }
    return params.base_color;
}

}  // namespace

std::optional<FirstHit> TraceFirstHit(const EmbreeScene& scene, const Ray& ray) {
    const std::optional<SurfaceHit> hit = scene.Intersect(ray);
    if (!hit) return std::nullopt;
    const Shading sh = Shade(scene, *hit, -ray.d);
    const Material& material = scene.scene().materials[size_t(hit->material)];
    return FirstHit{Albedo(material, sh.params), sh.ns, hit->t * Length(ray.d)};
}

}  // namespace lf
