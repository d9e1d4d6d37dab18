// What the two light samplers share about a scene's emitters: next-event estimation's
// LightSampler (lf/kernels/lights.h) and the emission sampler of light paths (EmissionSampler,
// lf/kernels/light_emission.h) must see the same spot falloff, the same sun disks (and the same
// fallback to a delta light), the same power measure and the same pick table, or the methods
// that use both (light tracing against path tracing, BDPT's weights) would disagree.
#pragma once

#include <numbers>
#include <optional>
#include <vector>

#include "lf/core/rgb.h"
#include "lf/core/scene.h"
#include "lf/core/vec.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/shading.h"

namespace lf {

// Power over the three channels: the average, not luminance, so that a pure blue light counts.
inline float LightPowerWeight(const Rgb& c) { return c.Average(); }

// The power weight of an area light of `area` and emission `emission` (pi A Le, twice that
// when it emits from both sides): the flux it sends out, in LightPowerWeight's measure.
inline double AreaLightWeight(float area, const Rgb& emission, bool two_sided) {
    return double(std::numbers::pi_v<float>) * area * LightPowerWeight(emission) *
           (two_sided ? 2 : 1);
}

// Both samplers' map from a triangle to its light: per mesh, per triangle, -1 to start with.
std::vector<std::vector<int>> NoTriangleLights(const Scene& scene);

// A triangle of an emissive mesh, as both samplers enumerate them.
struct EmissiveTriangle {
    int mesh, primitive;
    Vec3 p[3];  // render space
    float area;
    const Material* material;
    bool two_sided;  // emits from its back too (EmitsFromBack)
};

// Calls visit(const EmissiveTriangle&) for every triangle of positive area of every emissive
// mesh, mesh by mesh, in order; p is where it is at the shutter's opening, and a moving mesh's
// triangle's area is its largest at any step, so that one of no area at the opening that grows
// is still a light (its density at a time comes from EmbreeScene::TriangleArea). visit returns
// how many triangles it took: 1, or 2 when it made one light of this triangle and the next (a
// rectangle), which is then skipped.
template <typename Visit>
void ForEachEmissiveTriangle(const EmbreeScene& es, Visit&& visit) {
    const Scene& scene = es.scene();
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
        const Material& material = scene.materials[size_t(scene.meshes[m].material)];
        if (!material.IsEmissive()) continue;
        const size_t triangles = scene.meshes[m].triangles.size();
        for (size_t t = 0; t < triangles; ++t) {
            EmissiveTriangle tri{int(m), int(t), {}, 0, &material, EmitsFromBack(material)};
            es.Triangle(int(m), int(t), 0, &tri.p[0], &tri.p[1], &tri.p[2]);
            tri.area = TriangleAreaOf(tri.p[0], tri.p[1], tri.p[2]);
            if (es.Moves(int(m))) {
                for (int step = 1; step < es.steps(); ++step) {
                    const float time = float(step) / float(es.steps() - 1);
                    tri.area = std::max(tri.area, es.TriangleArea(int(m), int(t), time));
                }
            }
            if (!(tri.area > 0)) continue;
            t += size_t(visit(static_cast<const EmissiveTriangle&>(tri)) - 1);
        }
    }
}

// Sphere `s` of `scene` as an area light: its area and whether it emits from its back too;
// nullopt when its material does not emit.
struct SphereEmitter {
    float area;
    bool two_sided;
};
std::optional<SphereEmitter> EmissiveSphere(const Scene& scene, size_t s);

// 1 - cos(angle), exact also for angles so small that cos rounds to 1.
double OneMinusCos(double angle);

// A spot light's cone sizes as 1 - cos: the outer cone's, at least 1e-12 so that a cone of
// under a microradian still has a float extent, and the falloff band's width from there
// towards the axis, at least a millionth of the cone so that its slope stays finite when the
// cones (nearly) coincide.
struct SpotBand {
    double outer, width;
};
SpotBand SpotBandOf(const SpotLight& spot);

// The falloff as a function of t = (cos - cos outer) / width, clamped to [0, 1]: t^2
// (KHR_lights_punctual) or t^2 (3 - 2 t) (smoothstep).
inline float SpotBandFalloff(float t, bool smooth) { return smooth ? t * t * (3 - 2 * t) : t * t; }

// The solid angle a spot light's falloff integrates to: 2 pi times the integral of the falloff
// over cos in [-1, 1], which is 1 inside the band (1 - cos below outer - width) and the mean of
// t^2 (1/3) or of the smoothstep (1/2) over the band: positive for any cones.
double SpotFalloffSolidAngle(const SpotLight& spot);

// A sun disk: directions within angle alpha of `axis` (towards the sun) carry `radiance`.
// 1 - cos(alpha) is kept apart: for the sun (alpha = 0.0046) cos(alpha) in float is 1 to within
// 0.5 % of that difference.
struct SunDisk {
    Vec3 axis;
    float one_minus_cos;
    Rgb radiance;
    // w unit.
    bool Contains(const Vec3& w) const {
        // |w - axis|^2 = 2 (1 - cos): exact for small angles, where cos itself rounds to 1.
        return LengthSquared(w - axis) <= 2 * one_minus_cos;
    }
};

// A directional light's sun disk, radiance E / (pi sin^2 alpha) so that the disk facing a
// surface puts the light's irradiance on it; nullopt when the light is a delta light: no
// angular diameter, or a disk so small that its radiance or density overflows float.
std::optional<SunDisk> SunDiskOf(const DirectionalLight& light);

// Pick probabilities proportional to `weights` (uniform when they sum to 0) and their running
// sum, cdf.back() == 1.
struct LightPickTable {
    std::vector<float> pmf, cdf;

    static LightPickTable FromWeights(const std::vector<double>& weights);
    // The entry u (in [0, 1)) picks: the first whose cdf exceeds u.
    int Pick(float u) const;
};

}  // namespace lf
