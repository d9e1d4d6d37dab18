// KHR_materials_transmission tints what passes through by the base colour at every interface;
// KHR_materials_volume attenuates it inside by Beer's law. A smooth sphere in a uniform sky of
// radiance 1, seen along a diameter: every path that leaves it sees the sky, so with Fresnel F
// at normal incidence, base colour b and transmittance T over the diameter,
//   L = F + (1 - F) b T [(1 - F) b] sum_k (F T)^k = F + (1 - F)^2 b^2 T / (1 - F T),
// the front reflection plus what enters, crosses the diameter k + 1 times (k internal
// reflections, which are not tinted) and leaves through either end. A thin wall (thickness 0)
// is the same with T = 1: it neither bends nor attenuates.
#include <gtest/gtest.h>

#include <cmath>

#include "lf/kernels/embree_scene.h"
#include "lf/local/method_factory.h"
#include "point_estimate.h"

namespace lf {
namespace {

Scene TintedSphere(const Rgb& base, float thickness, float attenuation_distance) {
    Scene scene;
    Material glass;
    glass.type = Material::Type::kPrincipled;
    glass.reflectance = base;
    glass.roughness = 0;
    glass.transmission = 1;
    glass.thickness = thickness;
    glass.ior = 1.5f;
    glass.attenuation_color = Rgb(0.8f, 0.5f, 0.9f);
    glass.attenuation_distance = attenuation_distance;
    scene.materials.push_back(glass);
    scene.spheres.push_back({"glass", 0, Vec3d(), 0.5});
    scene.environment = EnvironmentLight{};
    AddAttenuationMedia(scene);
    return scene;
}

Rgb ClosedForm(const Material& m, double chord) {
    const double f = std::pow((m.ior - 1) / (m.ior + 1), 2);
    // Beer's law along the chord: attenuation_color after every attenuation_distance.
    Rgb t(1);
    if (m.HasInterior() && std::isfinite(m.attenuation_distance)) {
        for (int c = 0; c < 3; ++c) {
            t[c] = float(std::pow(m.attenuation_color[c], chord / m.attenuation_distance));
        }
    }
    Rgb l;
    for (int c = 0; c < 3; ++c) {
        const double b = m.reflectance[c];
        l[c] = float(f + (1 - f) * (1 - f) * b * b * t[c] / (1 - f * t[c]));
    }
    return l;
}

TEST(TransmissionTint, SphereCentreMatchesTheClosedForm) {
    for (const auto& [thickness, distance] :
         {std::pair(0.0f, 1.0f), std::pair(0.5f, std::numeric_limits<float>::infinity()),
          std::pair(0.5f, 0.7f)}) {
        SCOPED_TRACE(::testing::Message()
                     << "thickness " << thickness << " attenuation distance " << distance);
        const Scene scene = TintedSphere(Rgb(1, 0.5f, 0), thickness, distance);
        auto es = EmbreeScene::Build(scene);
        ASSERT_TRUE(es.ok()) << es.status();
        const std::unique_ptr<RadianceEstimator> tracer =
            MakeRayTracer(Method::kPath, **es, -1, LightStrategy::kBvh).value();
        const Ray ray = testing::RayBetween({0, 0, 3}, {0, 0, 0}, (*es)->origin());
        const testing::PointEstimate e = testing::EstimateRadiance(*tracer, ray, 40000, 5);
        const Rgb expected = ClosedForm(scene.materials[0], 1.0);
        // Red glass stays red: base colour 0 passes nothing but the front reflection.
        EXPECT_LT(e.mean[2], 0.05);
        // The smoothest GGX (alpha 1e-3) still scatters a few samples off the axis, where
        // Fresnel and the chord differ a little: the 2e-3 floor.
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(e.mean[c], expected[c], 5 * e.standard_error[c] + 2e-3)
                << "channel " << c << ", expected " << expected[c];
        }
    }
}

}  // namespace
}  // namespace lf
