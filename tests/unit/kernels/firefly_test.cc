// Fireflies (issue 28): in a room of smooth low-poly spheres (16 x 8 segments, vertex normals) of
// every material kind (a mirror-smooth clear coat over a rough base among them), lit by an emissive
// panel and by point, spot and directional lights, no single path-traced sample exceeds what the
// lights can deliver through the scene's rough lobes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/bsdf.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"

namespace lf {
namespace {

// Passes samples through and keeps the largest channel of any.
class MaxSample : public RadianceEstimator {
  public:
    explicit MaxSample(const RadianceEstimator& inner) : inner_(inner) {}
    Rgb Li(const Ray& ray, Sampler& sampler, RenderStats& stats) const override {
        const Rgb L = inner_.Li(ray, sampler, stats);
        std::lock_guard lock(mutex_);
        max_ = std::max(max_, L.MaxComponent());
        return L;
    }
    const EmbreeScene& geometry() const override { return inner_.geometry(); }
    float max() const { return max_; }

  private:
    const RadianceEstimator& inner_;
    mutable std::mutex mutex_;
    mutable float max_ = 0;
};

// The largest f(wo, wi) |cos_i| a material's non-delta lobes reach, over a grid of directions
// down to 1 degree above the horizon (reflection and transmission).
float PeakLobe(const Material& m) {
    const Bsdf bsdf(m);
    float peak = 0;
    constexpr int kSteps = 90;
    const auto at = [](int t, int p) {
        const double theta = (t + 0.5) * std::numbers::pi / 2 / kSteps;
        const double phi = p * std::numbers::pi / kSteps;
        return Vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                    float(std::cos(theta)));
    };
    for (int to = 0; to < kSteps; ++to) {
        const Vec3 wo = at(to, 0);
        for (int ti = 0; ti < kSteps; ++ti) {
            for (int p = 0; p <= kSteps; ++p) {
                const Vec3 wi = at(ti, p);
                for (const Vec3& w : {wi, Vec3(wi.x, wi.y, -wi.z)}) {
                    peak = std::max(peak, bsdf.Eval(wo, w).MaxComponent() * std::abs(w.z));
                }
            }
        }
    }
    return peak;
}

// A lower bound of the distance from p to any triangle of the scene: per triangle the larger of
// the distance to its plane and to its bounding sphere.
double NearestSurface(const Scene& scene, const Vec3d& p) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const TriangleMesh& mesh : scene.meshes) {
        for (const auto& t : mesh.triangles) {
            const Vec3d a = mesh.positions[t[0]], b = mesh.positions[t[1]],
                        c = mesh.positions[t[2]];
            const Vec3d centre = (a + b + c) / 3.0;
            const double radius =
                std::max({Length(a - centre), Length(b - centre), Length(c - centre)});
            const double plane = std::abs(Dot(Normalize(Cross(b - a, c - a)), p - a));
            nearest = std::min(nearest, std::max(plane, Length(p - centre) - radius));
        }
    }
    return nearest;
}

// A sample is a path's throughput (at most about 1: every sampled lobe's f |cos| / pdf is at
// most its albedo over its pick probability, and roulette lifts the largest channel to at most 1)
// times what its last vertex receives: an emitter's radiance through BSDF sampling or
// MIS-weighted light sampling (the power heuristic keeps f |cos| w / p_light below
// f |cos| / p_bsdf), or a delta light's irradiance E times f |cos|, which a rough lobe bounds
// by PeakLobe. Delta lobes (smooth surfaces) never meet a delta light. Bound: 4 times the
// larger of the brightest emitter's radiance and the largest E times the sharpest rough lobe's
// peak.
TEST(Fireflies, LargestSampleIsBoundedByTheLights) {
    auto scene = LoadScene(std::string(LF_TEST_SCENES) + "/firefly_room/firefly_room.json");
    ASSERT_TRUE(scene.ok()) << scene.status();

    float radiance = 0;
    for (const Material& m : scene->materials)
        radiance = std::max(radiance, m.emission.MaxComponent());
    double irradiance = 0;
    for (const PointLight& l : scene->point_lights) {
        const double d = NearestSurface(*scene, l.position);
        irradiance = std::max(irradiance, l.intensity.MaxComponent() / (d * d));
    }
    for (const SpotLight& l : scene->spot_lights) {
        const double d = NearestSurface(*scene, l.position);
        irradiance = std::max(irradiance, l.intensity.MaxComponent() / (d * d));
    }
    for (const DirectionalLight& l : scene->directional_lights) {
        irradiance = std::max(irradiance, double(l.irradiance.MaxComponent()));
    }
    // Roughness 0 is a perfect mirror (glTF): no rough lobe. So is a clear coat of roughness 0;
    // without it the base beneath only gets brighter (the coat's Keep is at most 1), so the
    // coat-less material's peak bounds the coated one's rough lobes.
    float peak = 0;
    for (Material m : scene->materials) {
        if (m.clearcoat_roughness == 0) m.clearcoat = 0;
        if (m.type != Material::Type::kPrincipled || m.roughness > 0)
            peak = std::max(peak, PeakLobe(m));
    }
    const double bound = 4 * std::max(double(radiance), irradiance * peak);

    auto es = EmbreeScene::Build(*scene);
    ASSERT_TRUE(es.ok()) << es.status();
    const Camera camera(scene->camera, (*es)->origin());
    const PathTracer tracer(**es, -1, LightStrategy::kBvh);
    const MaxSample probe(tracer);
    RenderSettings settings;
    settings.spp = 1024;
    settings.tile = 16;
    const auto out = RenderImage(camera, probe, settings);
    ASSERT_TRUE(out.ok()) << out.status();
    std::printf(
        "[fireflies] largest sample %.4g, bound %.4g (radiance %.3g, irradiance %.3g, "
        "peak f cos %.3g)\n",
        probe.max(), bound, radiance, irradiance, peak);
    EXPECT_LT(probe.max(), bound);
}

}  // namespace
}  // namespace lf
