// The principled material inside the path tracer: a plane of it under a directional light
// renders f(wo, wi) E cos(theta_i) at every point, f from the BSDF's own Eval. The render also
// makes the first use of the specular albedo table from inside the renderer's parallel loop.
#include <gtest/gtest.h>

#include <cmath>

#include "lf/kernels/bsdf.h"
#include "plane_render.h"
#include "render_path.h"

namespace lf {
namespace {

// The plane's normal is +y; a local frame with z along it. The BSDF is isotropic, so any
// tangents do, even a mirrored pair.
Vec3 PlaneLocal(const Vec3d& w) { return Vec3(Normalize(Vec3d(w.x, w.z, w.y))); }

TEST(PrincipledRender, PlaneUnderDirectionalLightMatchesEval) {
    for (float roughness : {0.3f, 0.8f}) {
        Scene scene = testing::PlaneUnderCamera(Rgb(0.8f, 0.5f, 0.2f));
        Material& m = scene.materials[0];
        m.type = Material::Type::kPrincipled;
        m.roughness = roughness;
        m.metallic = 0.3f;
        // The rougher plane wears a clear coat and a sheen: the renderer hands them to the BSDF.
        if (roughness > 0.5f) {
            m.clearcoat = 0.8f;
            m.clearcoat_roughness = 0.3f;
            m.sheen_color = Rgb(0.6f, 0.7f, 0.9f);
            m.sheen_roughness = 0.5f;
        }
        const DirectionalLight sun{Normalize(Vec3d(0.4, -1, 0.3)), Rgb(2.0f, 1.5f, 1.0f)};
        scene.directional_lights.push_back(sun);
        const uint64_t spp = 64;
        const RenderOutput out = testing::RenderPath(scene, spp).out;
        const Bsdf bsdf(m);
        const Vec3 wi = PlaneLocal(-sun.direction);
        const int compared =
            testing::ExpectPlaneMatches(scene, out.image, spp, [&](const Vec3d& x) {
                const Vec3 wo = PlaneLocal(scene.camera.position - x);
                return bsdf.Eval(wo, wi) * sun.irradiance * wi.z;
            });
        EXPECT_EQ(compared, testing::kPlaneImageSize * testing::kPlaneImageSize) << roughness;
    }
}

}  // namespace
}  // namespace lf
