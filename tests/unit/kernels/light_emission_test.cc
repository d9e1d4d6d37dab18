// EmissionSampler against closed forms: the flux Monte Carlo estimates from its samples equals
// each light's analytic power, its directions follow pdf_dir (chi-square), PdfLe gives back the
// densities it sampled with, and the first t = 1 connection (light tracing of direct light
// with Camera::SampleWi) reproduces a Lambertian plane's radiance under a point light.
#include "lf/kernels/light_emission.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <ostream>
#include <string>
#include <vector>

#include "chi_square.h"
#include "lf/core/camera.h"
#include "lf/core/sampler.h"
#include "lf/kernels/embree_scene.h"
#include "plane_render.h"
#include "render_path.h"
#include "sphere_quadrature.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

// A 2 x 1 quad in the plane y = 0 with normal +y, of material `material`.
void AddQuad(Scene& scene, int material, double y = 0) {
    TriangleMesh m;
    m.material = material;
    m.positions = {{-1, y, -0.5}, {-1, y, 0.5}, {1, y, 0.5}, {1, y, -0.5}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(m);
}

Scene WithGray() {
    Scene scene;
    scene.materials.push_back(Material{});  // material 0: grey, not emissive
    return scene;
}

int AddEmitter(Scene& scene, const Rgb& le, bool two_sided) {
    Material m;
    m.emission = le;
    m.two_sided_emission = two_sided;
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
}

// The spot falloff solid angle 2 pi times the integral of the falloff over cos in [-1, 1],
// written from the falloffs' definitions (lights_test's SpotFalloff) and integrated by
// quadrature.
double SpotSolidAngle(const SpotLight& spot) {
    const double scale = 1 / (std::cos(spot.inner_cone) - std::cos(spot.outer_cone));
    const auto falloff = [&](double c) {
        const double a = std::clamp((c - std::cos(spot.outer_cone)) * scale, 0.0, 1.0);
        return spot.falloff == SpotLight::Falloff::kSmoothstep ? a * a * (3 - 2 * a) : a * a;
    };
    return 2 * kPi *
           (testing::Integrate1D(falloff, std::cos(spot.outer_cone), std::cos(spot.inner_cone),
                                 64) +
            (1 - std::cos(spot.inner_cone)));
}

SpotLight Spot(SpotLight::Falloff falloff, double inner_deg, double outer_deg) {
    SpotLight spot;
    spot.position = {0.2, 1, -0.1};
    spot.direction = Normalize(Vec3d(0.3, -1, 0.2));
    spot.intensity = Rgb(6, 3, 1.5f);
    spot.inner_cone = testing::Radians(inner_deg);
    spot.outer_cone = testing::Radians(outer_deg);
    spot.falloff = falloff;
    return spot;
}

struct FluxCase {
    std::string name;
    std::function<Scene()> scene;
    // The analytic power (channel average) given the scene's bounding-sphere radius.
    std::function<double(double radius)> power;
};

std::vector<FluxCase> FluxCases() {
    const double sun_alpha = testing::Radians(5);
    return {
        {"OneSidedQuad",
         [] {
             Scene s = WithGray();
             AddQuad(s, AddEmitter(s, Rgb(2, 1, 3), false));
             return s;
         },
         [](double) { return kPi * 2 * 2; }},
        {"TwoSidedQuad",
         [] {
             Scene s = WithGray();
             AddQuad(s, AddEmitter(s, Rgb(2, 1, 3), true));
             return s;
         },
         [](double) { return 2 * kPi * 2 * 2; }},
        {"Sphere",
         [] {
             Scene s = WithGray();
             s.spheres.push_back({"lamp", AddEmitter(s, Rgb(1.5f), false), {0.3, 2, 0}, 0.4});
             return s;
         },
         [](double) { return kPi * 4 * kPi * 0.16 * 1.5; }},
        {"Point",
         [] {
             Scene s = WithGray();
             s.point_lights.push_back({{0, 1, 0}, Rgb(3, 6, 9)});
             return s;
         },
         [](double) { return 4 * kPi * 6; }},
        {"SpotSmoothstep",
         [] {
             Scene s = WithGray();
             s.spot_lights.push_back(Spot(SpotLight::Falloff::kSmoothstep, 20, 35));
             return s;
         },
         [](double) {
             return SpotSolidAngle(Spot(SpotLight::Falloff::kSmoothstep, 20, 35)) * 3.5;
         }},
        {"SpotKhr",
         [] {
             Scene s = WithGray();
             s.spot_lights.push_back(Spot(SpotLight::Falloff::kKhrLightsPunctual, 10, 60));
             return s;
         },
         [](double) {
             return SpotSolidAngle(Spot(SpotLight::Falloff::kKhrLightsPunctual, 10, 60)) * 3.5;
         }},
        {"Directional",
         [] {
             Scene s = WithGray();
             AddQuad(s, 0);
             s.directional_lights.push_back({Normalize(Vec3d(0.2, -1, 0.3)), Rgb(2, 4, 6)});
             return s;
         },
         [](double r) { return 4 * kPi * r * r; }},
        {"Sun",
         [=] {
             Scene s = WithGray();
             AddQuad(s, 0);
             s.directional_lights.push_back(
                 {Normalize(Vec3d(0.2, -1, 0.3)), Rgb(2, 4, 6), 2 * sun_alpha});
             return s;
         },
         // pi R^2 times the radiance E / (pi sin^2 alpha) over the cone's 2 pi (1 - cos alpha).
         [=](double r) {
             const double L = 4 / (kPi * std::sin(sun_alpha) * std::sin(sun_alpha));
             return kPi * r * r * L * 2 * kPi * (1 - std::cos(sun_alpha));
         }},
        {"Environment",
         [] {
             Scene s = WithGray();
             AddQuad(s, 0);
             s.environment = EnvironmentLight{Rgb(0.5f, 1, 1.5f), nullptr, 0};
             return s;
         },
         [](double r) { return kPi * r * r * 4 * kPi; }},
        {"AllAtOnce",
         [] {
             Scene s = WithGray();
             AddQuad(s, AddEmitter(s, Rgb(2, 1, 3), true), 0.5);
             s.point_lights.push_back({{0, 1, 0}, Rgb(3, 6, 9)});
             s.spot_lights.push_back(Spot(SpotLight::Falloff::kSmoothstep, 20, 35));
             s.environment = EnvironmentLight{Rgb(0.01f), nullptr, 0};
             return s;
         },
         [](double r) {
             return 2 * kPi * 2 * 2 + 4 * kPi * 6 +
                    SpotSolidAngle(Spot(SpotLight::Falloff::kSmoothstep, 20, 35)) * 3.5 +
                    kPi * r * r * 4 * kPi * 0.01;
         }},
    };
}

void PrintTo(const FluxCase& c, std::ostream* os) { *os << c.name; }

class EmissionFluxTest : public ::testing::TestWithParam<FluxCase> {};

INSTANTIATE_TEST_SUITE_P(Lights, EmissionFluxTest, ::testing::ValuesIn(FluxCases()),
                         [](const auto& info) { return info.param.name; });

// The mean of Le |cos| / (pick pdf_pos pdf_dir) is the emitted flux; and every sample's PdfLe
// is the densities it was drawn with.
TEST_P(EmissionFluxTest, FluxMatchesPowerAndPdfLeMatchesSample) {
    const Scene scene = GetParam().scene();
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    const EmissionSampler emission(**es);
    ASSERT_FALSE(emission.empty());
    const auto [lo, hi] = scene.Bounds();
    const double radius = Length(hi - lo) / 2;
    // A scene without geometry (a lone point or spot light) keeps a unit disk.
    EXPECT_NEAR(emission.scene_radius(), radius > 0 ? radius : 1, 1e-5 * std::max(radius, 1.0));
    constexpr int kSamples = 400'000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < kSamples; ++i) {
        Sampler sampler(std::hash<std::string>{}(GetParam().name), 0, 0, uint64_t(i));
        const float u_pick = sampler.Get1D();
        const Vec2 u_pos = sampler.Get2D(), u_dir = sampler.Get2D();
        const std::optional<EmissionSample> s = emission.Sample(u_pick, u_pos, u_dir, 0);
        if (!s) continue;
        ASSERT_NEAR(Length(s->w), 1, 1e-5);
        ASSERT_EQ(s->pick, emission.Pmf(s->light));
        // The emitter's cosine; point, spot and infinite lights set point.n = w (cos 1).
        const float cos = std::abs(Dot(s->point.n, s->w));
        const double f = s->le.Average() * cos / (s->pick * s->pdf_pos * s->pdf_dir);
        sum += f;
        sum2 += f * f;
        const EmissionPdf pdf = emission.PdfLe(s->light, s->point.p, s->point.n, s->w, 0);
        ASSERT_NEAR(pdf.pos, s->pdf_pos, 1e-5f * s->pdf_pos);
        ASSERT_NEAR(pdf.dir, s->pdf_dir, 1e-3f * s->pdf_dir) << "sample " << i;
    }
    const double mean = sum / kSamples;
    const double se = std::sqrt(std::max(0.0, sum2 / kSamples - mean * mean) / kSamples);
    const double expected = GetParam().power(radius);
    std::printf("[flux] %-16s %.5g +- %.3g, expected %.5g\n", GetParam().name.c_str(), mean, se,
                expected);
    EXPECT_NEAR(mean, expected, 5 * se + 1e-5 * expected);
}

// Samples that start on an area light leave it from a point on its surface, and a ray that hits
// the emitter maps back to the light the sample came from, with the same densities.
TEST(EmissionSamplerTest, HitsMapToTheirLight) {
    Scene scene = WithGray();
    AddQuad(scene, AddEmitter(scene, Rgb(1), false));
    scene.spheres.push_back({"lamp", AddEmitter(scene, Rgb(2), true), {0, 2, 0}, 0.3});
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const EmissionSampler emission(**es);
    ASSERT_EQ(emission.size(), 3u);  // two triangles and the sphere
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
        Sampler sampler(3, 0, 0, uint64_t(i));
        const float u_pick = sampler.Get1D();
        const Vec2 u_pos = sampler.Get2D(), u_dir = sampler.Get2D();
        const std::optional<EmissionSample> s = emission.Sample(u_pick, u_pos, u_dir, 0);
        ASSERT_TRUE(s);
        // Aim back at the sampled point from outside along its normal's side it emitted on.
        const Vec3 side = Dot(s->w, s->point.n) > 0 ? s->point.n : -s->point.n;
        const Vec3 from = s->point.p + side * 0.05f;
        const std::optional<SurfaceHit> hit = (*es)->Intersect(Ray{from, -side});
        if (!hit) continue;  // the quad's back face is culled for a one-sided emitter
        ++hits;
        EXPECT_LT(Length(hit->p - s->point.p), 1e-4f);
        const int light = emission.LightOf(*hit);
        EXPECT_EQ(light, s->light);
        const EmissionPdf pdf = emission.PdfLe(light, hit->p, hit->n, s->w, 0);
        EXPECT_NEAR(pdf.pos, s->pdf_pos, 1e-5f * s->pdf_pos);
        EXPECT_NEAR(pdf.dir, s->pdf_dir, 1e-3f * s->pdf_dir);
    }
    EXPECT_GT(hits, 1000);
}

// The directions a light emits in, histogrammed over the sphere (z up in the histogram, world
// directions as they are), against PdfLe integrated over each cell.
struct DirectionCase {
    std::string name;
    std::function<Scene()> scene;
};

void PrintTo(const DirectionCase& c, std::ostream* os) { *os << c.name; }

class EmissionDirectionTest : public ::testing::TestWithParam<DirectionCase> {};

INSTANTIATE_TEST_SUITE_P(
    Lights, EmissionDirectionTest,
    ::testing::Values(DirectionCase{"OneSidedQuad",
                                    [] {
                                        Scene s = WithGray();
                                        AddQuad(s, AddEmitter(s, Rgb(1), false));
                                        return s;
                                    }},
                      DirectionCase{"TwoSidedQuad",
                                    [] {
                                        Scene s = WithGray();
                                        AddQuad(s, AddEmitter(s, Rgb(1), true));
                                        return s;
                                    }},
                      DirectionCase{"Point",
                                    [] {
                                        Scene s = WithGray();
                                        s.point_lights.push_back({{0, 1, 0}, Rgb(1)});
                                        return s;
                                    }},
                      DirectionCase{"Spot",
                                    [] {
                                        Scene s = WithGray();
                                        s.spot_lights.push_back(
                                            Spot(SpotLight::Falloff::kSmoothstep, 30, 70));
                                        return s;
                                    }},
                      DirectionCase{"Sun",
                                    [] {
                                        Scene s = WithGray();
                                        AddQuad(s, 0);
                                        s.directional_lights.push_back(
                                            {Normalize(Vec3d(0.2, -1, 0.3)), Rgb(1),
                                             testing::Radians(60)});
                                        return s;
                                    }},
                      DirectionCase{"Environment",
                                    [] {
                                        Scene s = WithGray();
                                        AddQuad(s, 0);
                                        s.environment = EnvironmentLight{Rgb(1), nullptr, 0};
                                        return s;
                                    }}),
    [](const auto& info) { return info.param.name; });

TEST_P(EmissionDirectionTest, DirectionsFollowPdfDir) {
    using namespace testing;
    const Scene scene = GetParam().scene();
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const EmissionSampler emission(**es);
    // Lights with one normal throughout (a quad), or none: the density of w does not depend on
    // the point, so one histogram holds all samples.
    constexpr int kCells = kThetaRes * kPhiRes;
    std::vector<double> observed(kCells, 0.0);
    std::optional<EmissionSample> first;
    for (int i = 0; i < kChi2Samples; ++i) {
        Sampler sampler(std::hash<std::string>{}(GetParam().name), 0, 0, uint64_t(i));
        const float u_pick = sampler.Get1D();
        const Vec2 u_pos = sampler.Get2D(), u_dir = sampler.Get2D();
        const std::optional<EmissionSample> s = emission.Sample(u_pick, u_pos, u_dir, 0);
        ASSERT_TRUE(s);
        if (!first) first = s;
        const double theta = std::acos(std::clamp(double(s->w.z), -1.0, 1.0));
        double phi = std::atan2(double(s->w.y), double(s->w.x));
        if (phi < 0) phi += 2 * kPi;
        const int ti = std::min(int(theta / kPi * kThetaRes), kThetaRes - 1);
        const int pi = std::min(int(phi / (2 * kPi) * kPhiRes), kPhiRes - 1);
        ++observed[size_t(ti * kPhiRes + pi)];
    }
    std::vector<double> expected(kCells, 0.0);
    double integral = 0;
    for (int ti = 0; ti < kThetaRes; ++ti) {
        for (int pi = 0; pi < kPhiRes; ++pi) {
            const double p = IntegrateSolidAngle(
                [&](const Vec3& w) {
                    return double(
                        emission.PdfLe(first->light, first->point.p, first->point.n, w, 0).dir);
                },
                ti * kPi / kThetaRes, (ti + 1) * kPi / kThetaRes, pi * 2 * kPi / kPhiRes,
                (pi + 1) * 2 * kPi / kPhiRes, 4, 1e-7);
            expected[size_t(ti * kPhiRes + pi)] = p * kChi2Samples;
            integral += p;
        }
    }
    EXPECT_NEAR(integral, 1, 2e-3) << "pdf_dir does not integrate to 1";
    ExpectCountsMatch(observed, expected, GetParam().name, 6);
}

// Light tracing of direct light, the first t = 1 connection: a point light above a Lambertian
// plane of albedo rho, emitted rays hitting the plane connected to a pinhole by SampleWi. Each
// pixel's estimate (width height / paths times the sum of Le / (pick pdf_pos pdf_dir) f |cos|
// We / pdf over the connections landing in it) matches the closed form rho / pi I cos / r^2
// averaged over the pixel, within 5 of its standard errors, and the path tracer's image within
// the two methods' combined errors.
TEST(LightTracingConnectionTest, PointLightOverPlaneMatchesClosedFormAndPathTracer) {
    const Rgb rho(0.5f, 0.25f, 0.75f);
    Scene scene = testing::PlaneUnderCamera(rho);
    const PointLight light{{0.3, 1.5, -0.2}, Rgb(4, 2, 1)};
    scene.point_lights.push_back(light);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok());
    const EmissionSampler emission(**es);
    const Camera camera(scene.camera, (*es)->origin());
    const int w = camera.width(), h = camera.height();
    constexpr int kPaths = 8'000'000;
    std::vector<double> sum(size_t(w * h), 0.0), sum2(size_t(w * h), 0.0);
    for (int i = 0; i < kPaths; ++i) {
        Sampler sampler(5, 0, 0, uint64_t(i));
        const float u_pick = sampler.Get1D();
        const Vec2 u_pos = sampler.Get2D(), u_dir = sampler.Get2D();
        const std::optional<EmissionSample> s = emission.Sample(u_pick, u_pos, u_dir, 0);
        if (!s) continue;
        const std::optional<SurfaceHit> hit = (*es)->Intersect(s->ray());
        if (!hit) continue;
        const std::optional<Camera::ImportanceSample> c = camera.SampleWi(hit->p);
        if (!c) continue;
        // Both the light and the camera on the plane's front.
        if (!(Dot(c->wi, hit->n) > 0 && Dot(s->w, hit->n) < 0)) continue;
        const SurfacePoint at{hit->p, hit->p_error, hit->n};
        Ray shadow = SpawnRay(at, c->wi);
        shadow.t_max = Length(c->lens_point - shadow.o) * (1 - 1e-4f);
        if ((*es)->Occluded(shadow)) continue;
        // The channel average: rho's and I's channels multiply, so average their product.
        const Rgb beta = s->le * (1 / (s->pick * s->pdf_pos * s->pdf_dir));
        const double f = (beta * rho).Average() / kPi * Dot(c->wi, hit->n) * c->we / c->pdf;
        const size_t pixel = size_t(int(c->raster.y) * w + int(c->raster.x));
        sum[pixel] += f;
        sum2[pixel] += f * f;
    }
    const RenderOutput pt = testing::RenderPath(scene, 64).out;
    constexpr int kGrid = 24;
    int compared = 0;
    for (int py = 0; py < h; ++py) {
        for (int px = 0; px < w; ++px) {
            // The closed form over the pixel's footprint, its spread the path tracer's
            // per-sample deviation.
            double e = 0, e2 = 0;
            for (int j = 0; j < kGrid; ++j) {
                for (int i = 0; i < kGrid; ++i) {
                    const Ray r =
                        camera.GenerateRay(px, py, (i + 0.5f) / kGrid, (j + 0.5f) / kGrid);
                    const double t = -double(r.o.y) / r.d.y;
                    const Vec3d x(r.o.x + t * r.d.x, 0, r.o.z + t * r.d.z);
                    const Vec3d d = light.position - x;
                    const double dist2 = LengthSquared(d);
                    const double L =
                        (light.intensity * rho).Average() / kPi * d.y / (std::sqrt(dist2) * dist2);
                    e += L;
                    e2 += L * L;
                }
            }
            e /= kGrid * kGrid;
            const double pt_se = std::sqrt(std::max(0.0, e2 / (kGrid * kGrid) - e * e) / 64);
            const size_t pixel = size_t(py * w + px);
            const double n = kPaths;
            const double scale = double(w) * h;
            const double lt = scale * sum[pixel] / n;
            const double lt_se =
                scale *
                std::sqrt(std::max(0.0, sum2[pixel] / n - (sum[pixel] / n) * (sum[pixel] / n)) / n);
            EXPECT_NEAR(lt, e, 5 * lt_se + 1e-6) << "pixel " << px << ", " << py;
            const double pt_value = pt.image.Pixel(px, py).Average();
            EXPECT_NEAR(lt, pt_value, 5 * std::hypot(lt_se, pt_se) + 1e-6)
                << "pixel " << px << ", " << py;
            if (px % 5 == 0 && py % 5 == 0) {
                std::printf(
                    "[lt] pixel %2d %2d light tracing %.5f +- %.5f, closed form %.5f, "
                    "path tracer %.5f\n",
                    px, py, lt, lt_se, e, pt_value);
            }
            ++compared;
        }
    }
    EXPECT_EQ(compared, w * h);
}

}  // namespace
}  // namespace lf
