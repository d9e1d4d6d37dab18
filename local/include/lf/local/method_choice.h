// What `--method auto` and `plan` read from a scene description, without tracing a ray: which
// light transport the scene has, and so which method renders it best (Heckbert's notation:
// L light, D diffuse or glossy, S specular, E eye).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "lf/core/scene.h"
#include "lf/job/method_registry.h"

namespace lf {

struct SceneTransport {
    // Empty when radiosity models the scene exactly (diffuse materials, textured or not,
    // triangle meshes, any lights): else why not (lf/core/patch_mesh.h), or what it would drop.
    std::string radiosity_limitation;
    // Materials (by name) whose reflection or refraction is a delta or nearly so: mirrors,
    // dielectrics, transmissive principled materials, and glossy ones sharper than
    // kCausticRoughness. They focus light into caustics that only paths starting at the light
    // (or photons) find cheaply.
    std::vector<std::string> specular;
    bool diffuse = false;  // some surface reflects diffusely or glossily (a caustic's receiver)
    // Emitters small enough that a path tracer's camera paths rarely hit them after a specular
    // bounce, one phrase each: point and spot lights, directional lights and suns, and the area
    // emitters if their area is below kSmallEmitterFraction of the scene's bounding-box surface.
    std::vector<std::string> small_emitters;
    bool point_like_only = false;  // every light is a point, spot or directional light
    // Point, spot and directional lights without a disk: their caustics (L S+ D E with a delta
    // light) are paths the path tracer cannot sample at all (a BSDF sample never hits a point
    // light, a shadow ray never passes glass), so it converges to an image without them.
    std::vector<std::string> delta_lights;
    // What Whitted misses here (lf/kernels/whitted.h): empty when it is exact.
    std::vector<std::string> whitted_missing;

    // L S+ D E paths from a small emitter: caustics.
    bool caustics() const { return !specular.empty() && diffuse && !small_emitters.empty(); }
    // The caustics of delta lights: the path tracer (and Whitted) leave them out.
    bool delta_caustics() const { return !specular.empty() && diffuse && !delta_lights.empty(); }
};

// Glossy materials with a microfacet alpha below this behave as mirrors for caustics.
inline constexpr float kCausticRoughness = 0.1f;
// Area emitters below this fraction of the scene's bounding-box surface count as small (the
// Cornell box's lamp is 0.7 %).
inline constexpr double kSmallEmitterFraction = 0.02;

SceneTransport AnalyzeTransport(const Scene& scene);

struct MethodChoice {
    Method method;
    std::string why;
};

// `--method auto`: the path tracer for media only it and bdpt render (lf::MediaLimitation); whitted
// where it is exact (no interreflection, no caustics: it then equals the path tracer, faster,
// and has no meshing error); radiosity where it is exact (view-independent, noiseless); bdpt
// for caustics from small emitters; otherwise the path tracer.
MethodChoice ChooseAutomatically(const Scene& scene);

// `requested`, "requested"; or for nullopt (`--method auto`) ChooseAutomatically.
MethodChoice ChooseMethod(const Scene& scene, std::optional<Method> requested);

}  // namespace lf
