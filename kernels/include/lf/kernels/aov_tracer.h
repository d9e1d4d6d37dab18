// The first-hit AOVs (lf/core/aov.h) of a camera ray: what denoisers (OIDN, OptiX) take beside
// the noisy image, and the depth compositors use. One extra Embree ray per sample, traced apart
// from the radiance estimate and drawing no random numbers, so asking for AOVs leaves the image's
// bits alone. Alpha-mask holes and the culled back faces of single-sided meshes are passed
// through as the path tracer passes them.
#pragma once

#include <optional>

#include "lf/core/film.h"
#include "lf/core/ray.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/embree_scene.h"

namespace lf {

// The first surface `ray` hits, or nullopt for a miss (the AOVs then add nothing: albedo and
// normal average it as 0, depth leaves it out). Albedo follows OIDN's advice: the material's
// reflectance after textures for lambert (albedo) and principled (base colour), the specular
// tint for glossy (conductors: their Fresnel reflectance at normal incidence), and 1 for the
// perfectly specular mirror and dielectric, whose "albedo" is the scene behind them. The normal
// is the world-space shading normal (vertex normals, normal maps) on the front face's side;
// depth is the distance from the ray's origin (on the lens with depth of field).
std::optional<FirstHit> TraceFirstHit(const EmbreeScene& scene, const Ray& ray);

// What the illuminance estimates (RadianceEstimator::Irradiance) reflect the light arriving at a
// first hit with, in place of its material: a Lambertian of albedo 1, whose f = 1/pi makes pi
// times its reflected radiance the irradiance, whatever the surface does with the light.
Bsdf IrradianceBsdf();

}  // namespace lf
