// Scenes for the splatting methods (light tracing, BDPT, photon mapping), after pbrt-v4's
// integrator tests: a camera inside a diffuse sphere whose radiance is known in closed form.
#pragma once

#include <numbers>

#include "lf/core/scene.h"
#include "test_scenes.h"

namespace lf::testing {

// The closed-form radiance of both furnace spheres below.
inline constexpr double kFurnaceSphereRadiance = 1;

// A lambert sphere of albedo 0.5 and radius 1 at `center` (its inside seen: double-sided) with
// a point light of intensity pi at its centre, the camera there too. The irradiance on the wall
// is I / r^2 = pi, so the directly lit wall has radiance albedo E / pi = 0.5, and every bounce
// adds half of what the previous one had: L = 0.5 / (1 - 0.5) = 1 everywhere.
inline Scene PointLitFurnaceSphere(int resolution, const Vec3d& center = {0.3, -0.2, 0.1}) {
    Scene scene;
    Material m;
    m.name = "furnace";
    m.reflectance = Rgb(0.5f);
    scene.materials.push_back(m);
    scene.spheres.push_back({"sphere", 0, center, 1});
    scene.point_lights.push_back({center, Rgb(std::numbers::pi_v<float>)});
    scene.camera = SquareCamera(center, center + Vec3d(0.3, 0.2, 1), {0, 1, 0}, 60, resolution);
    return scene;
}

// The same sphere emitting Le = 0.5 from both sides instead of the light (the camera sees its
// inside): L = Le + 0.5 L, so L = 1 everywhere.
inline Scene EmissiveFurnaceSphere(int resolution, const Vec3d& center = {0.3, -0.2, 0.1}) {
    Scene scene = PointLitFurnaceSphere(resolution, center);
    scene.point_lights.clear();
    scene.materials[0].emission = Rgb(0.5f);
    scene.materials[0].two_sided_emission = true;
    return scene;
}

}  // namespace lf::testing
