#include "lf/local/method_choice.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "lf/core/patch_mesh.h"
#include "lf/kernels/whitted.h"

namespace lf {

namespace {

bool FocusesLight(const Material& m) {
    switch (m.type) {
        case Material::Type::kMirror:
        case Material::Type::kDielectric:
            return true;
        case Material::Type::kGlossy:
            return m.roughness < kCausticRoughness;
        case Material::Type::kPrincipled:
            // glTF's perceptual roughness r is alpha = r^2; a smooth metal or a clear
            // transmitter focuses light.
            return (m.transmission > 0 || m.metallic > 0.5f) &&
                   m.roughness * m.roughness < kCausticRoughness;
        case Material::Type::kLambert:
        case Material::Type::kInterface:  // passes light straight on
            return false;
    }
    return false;
}

bool Scatters(const Material& m) {
    if (FocusesLight(m) || m.type == Material::Type::kInterface) return false;
    return m.type != Material::Type::kLambert || !m.reflectance.IsBlack();
}

double TriangleArea(const TriangleMesh& mesh, const std::array<uint32_t, 3>& t) {
    const Vec3d& a = mesh.positions[t[0]];
    return 0.5 * Length(Cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a));
}

}  // namespace

SceneTransport AnalyzeTransport(const Scene& scene) {
    SceneTransport out;
    out.radiosity_limitation = RadiosityLimitation(scene);
    if (const std::string drops = RadiosityDrops(scene);
        out.radiosity_limitation.empty() && !drops.empty()) {
        out.radiosity_limitation =
            "radiosity would keep only the diffuse parts (dropping " + drops + ")";
    }
    out.whitted_missing = WhittedMissingTerms(scene);

    std::vector<bool> used(scene.materials.size(), false);
    std::vector<double> emitting_area(scene.materials.size(), 0);
    for (const TriangleMesh& mesh : scene.meshes) {
        used[size_t(mesh.material)] = true;
        for (const auto& t : mesh.triangles) {
            emitting_area[size_t(mesh.material)] += TriangleArea(mesh, t);
        }
    }
    for (const Sphere& s : scene.spheres) {
        used[size_t(s.material)] = true;
        emitting_area[size_t(s.material)] += 4 * std::numbers::pi * s.radius * s.radius;
    }
    const auto [lo, hi] = scene.Bounds();
    const Vec3d d = hi - lo;
    const double box_area = 2 * (d.x * d.y + d.y * d.z + d.z * d.x);

    bool area_lights = false;
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        if (!used[i]) continue;
        if (FocusesLight(m)) out.specular.push_back(m.name);
        if (Scatters(m)) out.diffuse = true;
        if (!m.IsEmissive()) continue;
        area_lights = true;
        // A scene without finite bounds has no size to compare with: nothing counts as small.
        const double fraction =
            box_area > 0 && std::isfinite(box_area) ? emitting_area[i] / box_area : 1;
        if (fraction < kSmallEmitterFraction) {
            out.small_emitters.push_back(
                absl::StrFormat("emitter \"%s\" (%.2g %% of the scene's bounding surface)", m.name,
                                100 * fraction));
        }
    }
    const auto count = [](size_t n, const char* what) {
        return absl::StrCat(n, " ", what, n == 1 ? "" : "s");
    };
    if (!scene.point_lights.empty()) {
        out.small_emitters.push_back(count(scene.point_lights.size(), "point light"));
    }
    if (!scene.spot_lights.empty()) {
        out.small_emitters.push_back(count(scene.spot_lights.size(), "spot light"));
    }
    if (!scene.directional_lights.empty()) {
        out.small_emitters.push_back(
            count(scene.directional_lights.size(), "directional light or sun"));
    }
    if (!scene.point_lights.empty()) {
        out.delta_lights.push_back(count(scene.point_lights.size(), "point light"));
    }
    if (!scene.spot_lights.empty()) {
        out.delta_lights.push_back(count(scene.spot_lights.size(), "spot light"));
    }
    const size_t parallel =
        size_t(std::count_if(scene.directional_lights.begin(), scene.directional_lights.end(),
                             [](const DirectionalLight& l) { return !(l.angular_diameter > 0); }));
    if (parallel > 0) {
        out.delta_lights.push_back(count(parallel, "directional light without a sun disk"));
    }
    out.point_like_only = !area_lights && !scene.environment &&
                          (!scene.point_lights.empty() || !scene.spot_lights.empty() ||
                           !scene.directional_lights.empty());
    return out;
}

MethodChoice ChooseAutomatically(const Scene& scene) {
    const SceneTransport t = AnalyzeTransport(scene);
    // No light: every method renders black; no form factors or pilots to spend on it.
    if (!scene.HasLights()) {
        return {Method::kPath, "the scene has no lights: the image is black whatever the method"};
    }
    // Scattering, emitting or grid media: every method but the path tracer and bdpt (which
    // refuses emissive media) refuses them (MediaLimitation); the path tracer is the reference.
    if (const std::string media = MediaLimitation(scene); !media.empty()) {
        return {Method::kPath, absl::StrCat(media, BdptMediaLimitation(scene).empty()
                                                       ? ": only the path tracer and bdpt render it"
                                                       : ": only the path tracer renders it")};
    }
    // Whitted before radiosity: where it is exact it has no meshing error either.
    if (t.whitted_missing.empty() && scene.HasLights()) {
        return {Method::kWhitted,
                absl::StrCat("no interreflection and no caustics: classic ray tracing is exact "
                             "here",
                             t.point_like_only ? " (point-like lights only)" : "")};
    }
    if (t.radiosity_limitation.empty()) {
        return {Method::kRadiosity, "every material is Lambertian"};
    }
    if (t.caustics()) {
        return {
            Method::kBdpt,
            absl::StrCat("caustics (L S+ D E): light from ", absl::StrJoin(t.small_emitters, ", "),
                         " through ", absl::StrJoin(t.specular, ", "),
                         t.delta_caustics()
                             ? "; the path tracer cannot sample those of the " +
                                   absl::StrJoin(t.delta_lights, ", ") + " at all"
                             : "; camera paths find them only by hitting a small emitter")};
    }
    return {Method::kPath, t.radiosity_limitation};
}

MethodChoice ChooseMethod(const Scene& scene, std::optional<Method> requested) {
    if (requested) return {*requested, "requested"};
    return ChooseAutomatically(scene);
}

}  // namespace lf
