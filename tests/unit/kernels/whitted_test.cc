// Whitted ray tracing as the path tracer's special case: against closed forms (a point light
// on a Lambertian plane; a glass sphere refracting a two-coloured wall, traced by hand) and
// against the path tracer where the two estimate the same integral (direct light at depth 1;
// a diffuse floor seen directly and through a mirror sphere; a glass sphere between emitters),
// the path tracer's point estimates with their standard errors giving the tolerance.
#include "lf/kernels/whitted.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>

#include "lf/core/camera.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/path_tracer.h"
#include "lf/local/local_executor.h"
#include "plane_render.h"
#include "point_estimate.h"
#include "splat_scenes.h"
#include "test_scenes.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

std::unique_ptr<EmbreeScene> Build(const Scene& scene) {
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    return std::move(*es);
}

using testing::AddQuad;

int AddMaterial(Scene& scene, Material::Type type, const Rgb& reflectance,
                const Rgb& emission = Rgb(0.0f)) {
    Material m;
    m.type = type;
    m.reflectance = reflectance;
    m.emission = emission;
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
}

// Expects Whitted's and the path tracer's estimates along `ray` to agree within k standard
// errors of their difference (each from its own samples' spread).
void ExpectSameRadiance(const RadianceEstimator& whitted, const RadianceEstimator& path,
                        const Ray& ray, int n, const char* what, double k = 5) {
    const testing::PointEstimate w = testing::EstimateRadiance(whitted, ray, n, 7);
    const testing::PointEstimate p = testing::EstimateRadiance(path, ray, n, 11);
    for (int c = 0; c < 3; ++c) {
        const double se = std::hypot(w.standard_error[c], p.standard_error[c]);
        EXPECT_NEAR(w.mean[c], p.mean[c], k * se + 1e-5 * std::abs(p.mean[c]))
            << what << ", channel " << c << ", path standard error " << p.standard_error[c];
    }
}

// A point light over a Lambertian plane: L = rho / pi * I cos(theta) / r^2 at every pixel, and
// Whitted's one light sample per pixel sample is exact, so only the pixel footprint varies.
TEST(Whitted, PointLightOnLambertianPlaneMatchesClosedForm) {
    const Rgb rho(0.5f, 0.25f, 0.75f);
    Scene scene = testing::PlaneUnderCamera(rho);
    const PointLight light{Vec3d(0.4, 1.2, -0.3), Rgb(6.0f, 3.0f, 1.5f)};
    scene.point_lights.push_back(light);
    const auto es = Build(scene);
    const WhittedTracer tracer(*es, -1);
    RenderSettings settings;
    settings.spp = 16;
    settings.tile = 8;
    const RenderOutput out =
        RenderImage(Camera(scene.camera, es->origin()), tracer, settings).value();
    const int compared =
        testing::ExpectPlaneMatches(scene, out.image, settings.spp, [&](const Vec3d& x) {
            const Vec3d d = light.position - x;
            const double r2 = LengthSquared(d);
            const double cos_theta = d.y / std::sqrt(r2);
            return rho * light.intensity * float(cos_theta / (kPi * r2));
        });
    EXPECT_EQ(compared, testing::kPlaneImageSize * testing::kPlaneImageSize);
}

// Every delta light gets its own shadow ray at every hit, as in Whitted's ray tracer: with three
// point lights (one behind a wall that shadows the point) the radiance along a ray is the same
// in every sample, the closed-form sum of the unshadowed ones.
TEST(Whitted, SumsEveryDeltaLightWithoutNoise) {
    const Rgb rho(0.6f, 0.4f, 0.2f);
    Scene scene = testing::PlaneUnderCamera(rho);
    const PointLight lights[] = {{Vec3d(0.5, 1.0, 0.2), Rgb(3.0f)},
                                 {Vec3d(-0.8, 2.0, -0.4), Rgb(1.0f, 2.0f, 4.0f)},
                                 {Vec3d(3.0, 0.5, 0.0), Rgb(50.0f)}};
    for (const PointLight& light : lights) scene.point_lights.push_back(light);
    // A wall at x = 2 (normal -x) between the third light and the point.
    AddQuad(scene, 0, {2, 0, -5}, {2, 5, -5}, {2, 5, 5}, {2, 0, 5});
    const auto es = Build(scene);
    const WhittedTracer tracer(*es, -1);
    const Vec3d x(0.1, 0, 0.05);
    Rgb expected;
    for (int i = 0; i < 2; ++i) {
        const Vec3d d = lights[i].position - x;
        const double r2 = LengthSquared(d);
        expected += rho * lights[i].intensity * float(d.y / std::sqrt(r2) / (kPi * r2));
    }
    const testing::PointEstimate e = testing::EstimateRadiance(
        tracer, testing::RayBetween(x + Vec3d(0, 1, 0.2), x, es->origin()), 64);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(e.mean[c], expected[c], 1e-4 * expected[c]) << "channel " << c;
        EXPECT_LE(e.sample_sd[c], 1e-6 * expected[c]) << "channel " << c;
    }
}

// pbrt's furnace spheres (splat_scenes.h) have radiance 1 from their interreflection; Whitted
// keeps the emission and the direct light only: with the point light albedo x E / pi = 0.5,
// exactly and without noise; the emissive sphere 0.5 + 0.5 x 0.5 = 0.75 (the sphere is its own
// area light), within the noise of sampling it.
TEST(Whitted, FurnaceSpheresKeepTheirDirectTermOnly) {
    for (const bool emissive : {false, true}) {
        const Scene scene =
            emissive ? testing::EmissiveFurnaceSphere(8) : testing::PointLitFurnaceSphere(8);
        const auto es = Build(scene);
        const WhittedTracer tracer(*es, -1);
        const Camera camera(scene.camera, es->origin());
        for (const auto& [px, py] : {std::pair{0, 0}, {3, 5}, {7, 7}}) {
            constexpr int kSamples = 1024;
            const testing::PointEstimate e = testing::EstimateRadiance(
                tracer, camera.GenerateRay(px, py, 0.5f, 0.5f, Vec2{}), kSamples);
            if (emissive) {
                EXPECT_NEAR(e.mean[1], 0.75, 5 * e.sample_sd[1] / std::sqrt(kSamples) + 1e-6);
            } else {
                EXPECT_NEAR(e.mean[1], 0.5, 1e-4);
                EXPECT_LE(e.sample_sd[1], 1e-6);
            }
        }
    }
}

// At max depth 1 both methods estimate emission plus direct light at the first hit (and what a
// mirror shows at its first bounce, emission only): a grey box with a point light, a quad area
// light under the ceiling and a mirror sphere, seen along rays to walls, floor, lamp and mirror.
TEST(Whitted, EqualsPathTracerAtDepthOne) {
    Scene scene;
    const int wall = AddMaterial(scene, Material::Type::kLambert, Rgb(0.6f, 0.5f, 0.4f));
    const int lamp = AddMaterial(scene, Material::Type::kLambert, Rgb(0.0f), Rgb(4.0f, 3.0f, 2.0f));
    const int mirror = AddMaterial(scene, Material::Type::kMirror, Rgb(0.9f, 0.8f, 0.9f));
    testing::AddInwardBox(scene, Vec3d(), 1, wall);
    AddQuad(scene, lamp, {-0.3, 0.95, -0.3}, {0.3, 0.95, -0.3}, {0.3, 0.95, 0.3},
            {-0.3, 0.95, 0.3});  // normal -y
    scene.spheres.push_back({"mirror", mirror, Vec3d(-0.35, -0.6, 0.1), 0.35});
    scene.point_lights.push_back({Vec3d(0.5, 0.5, 0.6), Rgb(1.0f, 1.5f, 2.0f)});
    scene.camera = testing::SquareCamera({0, 0, 0.9}, {0, 0, 0}, {0, 1, 0}, 60, 8);
    const auto es = Build(scene);
    const WhittedTracer whitted(*es, 1);
    const PathTracer path(*es, 1);
    const Vec3d from(0.1, 0.05, 0.9);
    const struct {
        Vec3d to;
        const char* what;
    } targets[] = {{{0.2, -1, -0.3}, "floor"},      {{-1, 0.2, 0.1}, "left wall"},
                   {{0.3, 0.4, -1}, "back wall"},   {{0.05, 0.95, 0.1}, "lamp"},
                   {{-0.35, -0.45, 0.2}, "mirror"}, {{-0.25, -0.55, 0.3}, "mirror rim"}};
    for (const auto& t : targets) {
        ExpectSameRadiance(whitted, path, testing::RayBetween(from, t.to, es->origin()), 4096,
                           t.what);
    }
}

// A diffuse floor, a specular sphere on it and a point light: no diffuse surface sees another,
// so at max depth 2 the path tracer's only terms are direct light at the floor, seen directly
// or in the sphere, which is all Whitted computes: the two agree, shadow and reflection
// included. The sphere is a mirror, or a smooth principled dielectric over a black base: a
// BSDF with a delta lobe and a (black) diffuse one, whose reflection Whitted used to drop
// because the surface was not all delta.
void ExpectEqualsPathTracerThroughSpecularSphere(const Material& sphere_material) {
    Scene scene;
    const int floor = AddMaterial(scene, Material::Type::kLambert, Rgb(0.7f, 0.6f, 0.3f));
    scene.materials.push_back(sphere_material);
    const int sphere = int(scene.materials.size()) - 1;
    AddQuad(scene, floor, {-20, 0, -20}, {-20, 0, 20}, {20, 0, 20}, {20, 0, -20});  // normal +y
    scene.spheres.push_back({"sphere", sphere, Vec3d(0, 1, 0), 1});
    scene.point_lights.push_back({Vec3d(1.5, 3, 1), Rgb(20.0f, 18.0f, 15.0f)});
    scene.camera = testing::SquareCamera({0, 1.5, 5}, {0, 1, 0}, {0, 1, 0}, 40, 8);
    const auto es = Build(scene);
    const WhittedTracer whitted(*es, 2);
    const PathTracer path(*es, 2);
    const Vec3d from = scene.camera.position;
    const struct {
        Vec3d to;
        const char* what;
    } targets[] = {{{0.8, 0, 2}, "floor, lit"},
                   {{-0.9, 0, -1.5}, "floor, in the sphere's shadow"},
                   {{0.3, 0.4, 0.9}, "sphere, showing the floor"},
                   {{-0.6, 0.3, 0.75}, "sphere, showing the floor at an angle"},
                   {{0.2, 1.6, 0.95}, "sphere, showing the sky"}};
    for (const auto& t : targets) {
        ExpectSameRadiance(whitted, path, testing::RayBetween(from, t.to, es->origin()), 4096,
                           t.what);
    }
}

TEST(Whitted, EqualsPathTracerThroughMirror) {
    Material mirror;
    mirror.type = Material::Type::kMirror;
    mirror.reflectance = Rgb(0.95f, 0.9f, 0.8f);
    ExpectEqualsPathTracerThroughSpecularSphere(mirror);
}

TEST(Whitted, EqualsPathTracerThroughSmoothPrincipledOverABlackBase) {
    Material plastic;
    plastic.type = Material::Type::kPrincipled;
    plastic.reflectance = Rgb(0.0f);
    plastic.roughness = 0;
    plastic.ior = 2.5f;  // F0 = 0.18: a reflection well above the noise
    ExpectEqualsPathTracerThroughSpecularSphere(plastic);
}

// A smooth clear coat over a smooth metal: all delta, its coat and base reflecting in one
// direction; the deterministic split used to follow the coat's lobe alone.
TEST(Whitted, EqualsPathTracerThroughSmoothCoatedMetal) {
    Material paint;
    paint.type = Material::Type::kPrincipled;
    paint.reflectance = Rgb(0.9f, 0.6f, 0.3f);
    paint.metallic = 1;
    paint.roughness = 0;
    paint.clearcoat = 1;
    paint.clearcoat_roughness = 0;
    ExpectEqualsPathTracerThroughSpecularSphere(paint);
}

// Unpolarised Fresnel reflectance from the definition, for light arriving at cos_i > 0 from
// the side of index n1 onto index n2; 1 under total internal reflection.
double Fresnel(double cos_i, double n1, double n2) {
    const double sin_t = n1 / n2 * std::sqrt(std::max(0.0, 1 - cos_i * cos_i));
    if (sin_t >= 1) return 1;
    const double cos_t = std::sqrt(1 - sin_t * sin_t);
    const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return (rs * rs + rp * rp) / 2;
}

// Snell's law for unit d arriving at a surface with unit normal n facing it (Dot(d, n) < 0).
Vec3d Refracted(const Vec3d& d, const Vec3d& n, double n1, double n2) {
    const double eta = n1 / n2, cos_i = -Dot(d, n);
    const double cos_t = std::sqrt(1 - eta * eta * (1 - cos_i * cos_i));
    return d * eta + n * (eta * cos_i - cos_t);
}

// A unit glass sphere (IOR 1.5) at the origin in front of an emitting wall at z = -3: red for
// x < 0, green for x > 0, and nothing else in the scene.
constexpr double kIor = 1.5, kWallZ = -3;
Scene GlassBeforeWall() {
    Scene scene;
    Material glass;
    glass.type = Material::Type::kDielectric;
    glass.ior = float(kIor);
    scene.materials.push_back(glass);
    const int red = AddMaterial(scene, Material::Type::kLambert, Rgb(0.0f), Rgb(1.0f, 0.0f, 0.0f));
    const int green =
        AddMaterial(scene, Material::Type::kLambert, Rgb(0.0f), Rgb(0.0f, 1.0f, 0.0f));
    const double z = kWallZ;
    AddQuad(scene, red, {-20, -20, z}, {0, -20, z}, {0, 20, z}, {-20, 20, z});  // normal +z
    AddQuad(scene, green, {0, -20, z}, {20, -20, z}, {20, 20, z}, {0, 20, z});  // normal +z
    scene.spheres.push_back({"glass", 0, Vec3d(), 1});
    scene.camera = testing::SquareCamera({0, 0, 10}, {0, 0, 0}, {0, 1, 0}, 20, 8);
    return scene;
}

// A ray parallel to the axis at height h > 0 enters the sphere, refracts twice and, past the
// ball lens's focus, lands on the red half, where the straight line would land on the green
// one. Whitted's value is the red emission times both Fresnel transmittances (the 1 / eta^2 of
// entering and eta^2 of leaving cancel), plus what the internally reflected rays find, which
// carry at most the energy neither the first reflection nor the straight transmission took.
TEST(Whitted, GlassSphereShowsTheRefractedWall) {
    const Scene scene = GlassBeforeWall();
    const auto es = Build(scene);
    const WhittedTracer tracer(*es, -1);
    for (double h : {0.3, 0.5, 0.7}) {
        SCOPED_TRACE(h);
        const Vec3d d(0, 0, -1);
        const Vec3d p1(h, 0, std::sqrt(1 - h * h));  // entry; its normal is p1
        const double cos1 = -Dot(d, p1);
        const Vec3d d1 = Refracted(d, p1, 1, kIor);
        const Vec3d p2 = p1 + d1 * (-2 * Dot(p1, d1));  // the chord's other end
        const double cos2 = Dot(d1, p2);
        const Vec3d d2 = Refracted(d1, -p2, kIor, 1);
        const double landing_x = p2.x + d2.x * (kWallZ - p2.z) / d2.z;
        ASSERT_LT(landing_x, -0.1) << "the test's ray must land on the red half";

        const double r1 = Fresnel(cos1, 1, kIor), r2 = Fresnel(cos2, kIor, 1);
        const double transmitted = (1 - r1) * (1 - r2);
        const double rest = 1 - r1 - transmitted;  // the internal reflection's share
        RenderStats stats;
        Sampler sampler(1, 0, 0, 0);
        const Rgb L = tracer.Li(Ray{Vec3(Vec3d(h, 0, 10) - es->origin()), Vec3(d)}, sampler, stats);
        EXPECT_GE(L.r, transmitted * (1 - 1e-4));
        EXPECT_LE(L.r, transmitted + rest + 1e-4);
        EXPECT_LE(L.g, rest + 1e-4);
        EXPECT_EQ(L.b, 0);
        EXPECT_GT(stats.rays, 3u) << "both lobes at every glass hit";
    }
}

// With no diffuse reflector, Whitted's deterministic Fresnel splitting and the path tracer's
// random choice between reflection and refraction (with roulette, unlimited depth) estimate
// the same sum over specular chains, total internal reflection included; Whitted cuts it at
// kWhittedUnlimitedDepth, where a chain keeps at most (its internal reflectance)^8.
TEST(Whitted, FresnelSplittingEqualsPathTracerChoice) {
    const Scene scene = GlassBeforeWall();
    const auto es = Build(scene);
    const WhittedTracer whitted(*es, -1);
    const PathTracer path(*es, -1);
    for (double h : {0.0, 0.45, 0.8, 0.97}) {
        SCOPED_TRACE(h);
        const Vec3d from(h, 0.1, 10);
        ExpectSameRadiance(whitted, path,
                           testing::RayBetween(from, from + Vec3d(0.02, 0, -1), es->origin()), 8192,
                           "through the glass");
    }
}

// Delta lights only, as in the closed forms above, but a direct-light-only estimator must still
// see an area light: a Lambertian plane under a quad emitter, the point straight below it.
TEST(Whitted, AreaLightIsSampledWithShadowRays) {
    Scene scene = testing::PlaneUnderCamera(Rgb(0.5f));
    const int lamp = AddMaterial(scene, Material::Type::kLambert, Rgb(0.0f), Rgb(3.0f));
    AddQuad(scene, lamp, {-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0.5, 1, 0.5}, {-0.5, 1, 0.5});
    const auto es = Build(scene);
    const WhittedTracer tracer(*es, -1);
    // A unit square at height 1 centred over the point: the form factor to a parallel
    // rectangle with half-sides a = b = 0.5 at distance 1 (Hottel's closed form), times pi:
    // E = L * pi * F, and the plane's radiance is rho E / pi = rho L F.
    const double x = 0.5, y = 0.5;  // half sides over the distance
    const double f = 4 *
                     (x / std::sqrt(1 + x * x) * std::atan(y / std::sqrt(1 + x * x)) +
                      y / std::sqrt(1 + y * y) * std::atan(x / std::sqrt(1 + y * y))) /
                     (2 * kPi);
    const testing::PointEstimate e = testing::EstimateRadiance(
        tracer, testing::RayBetween({0, 0.9, 0.05}, {0, 0, 0}, es->origin()), 4096);
    testing::ExpectEstimateNear(e, Rgb(float(0.5 * 3 * f)));
}

// The rule of WhittedMissingTerms on scenes whose answer is plain: one lit plane, and one
// diffuse sphere on its own, see nothing of themselves (exact); a plane with a mirror sphere
// lacks only caustics; a closed box lacks interreflection; a diffuse sphere on a plane, both.
TEST(Whitted, MissingTermsFollowTheSceneRule) {
    const auto has = [](const std::vector<std::string>& terms, const char* word) {
        for (const std::string& t : terms) {
            if (t.find(word) != std::string::npos) return true;
        }
        return false;
    };
    Scene plane = testing::PlaneUnderCamera(Rgb(0.5f));
    plane.point_lights.push_back({Vec3d(0, 1, 0), Rgb(1.0f)});
    EXPECT_TRUE(WhittedMissingTerms(plane).empty());

    Scene ball;
    AddMaterial(ball, Material::Type::kLambert, Rgb(0.5f));
    ball.spheres.push_back({"ball", 0, Vec3d(), 1});
    EXPECT_TRUE(WhittedMissingTerms(ball).empty());

    Scene mirror = plane;
    const int chrome = AddMaterial(mirror, Material::Type::kMirror, Rgb(0.9f));
    mirror.spheres.push_back({"mirror", chrome, Vec3d(0, 1, 0), 0.5});
    const std::vector<std::string> caustics = WhittedMissingTerms(mirror);
    EXPECT_EQ(caustics.size(), 1u);
    EXPECT_TRUE(has(caustics, "caustics"));

    // Emitters and black surfaces reflect nothing: a glass sphere between emitting walls misses
    // nothing (and FresnelSplittingEqualsPathTracerChoice checks it converges there).
    EXPECT_TRUE(WhittedMissingTerms(GlassBeforeWall()).empty());

    Scene box;
    AddMaterial(box, Material::Type::kLambert, Rgb(0.5f));
    testing::AddInwardBox(box, Vec3d(), 1, 0);
    const std::vector<std::string> room = WhittedMissingTerms(box);
    EXPECT_EQ(room.size(), 1u);
    EXPECT_TRUE(has(room, "interreflection"));

    Scene both = mirror;
    both.spheres.push_back({"ball", 0, Vec3d(2, 1, 0), 0.5});
    const std::vector<std::string> all = WhittedMissingTerms(both);
    EXPECT_TRUE(has(all, "interreflection"));
    EXPECT_TRUE(has(all, "caustics"));

    // A smooth principled sphere reflects the light as a mirror does (its delta lobe), over a
    // diffuse base that sees the plane: caustics and interreflection.
    Scene plastic = plane;
    Material smooth;
    smooth.type = Material::Type::kPrincipled;
    smooth.roughness = 0;
    plastic.materials.push_back(smooth);
    plastic.spheres.push_back({"plastic", int(plastic.materials.size()) - 1, Vec3d(0, 1, 0), 0.5});
    const std::vector<std::string> smooth_terms = WhittedMissingTerms(plastic);
    EXPECT_TRUE(has(smooth_terms, "caustics"));
    EXPECT_TRUE(has(smooth_terms, "interreflection"));
}

}  // namespace
}  // namespace lf
