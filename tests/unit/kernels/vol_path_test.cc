// Volumetric path tracing against closed forms and an independent random walk: Beer's law
// through a slab, the furnace of a non-absorbing sphere, a scattering sphere's escape
// probability, grids against homogeneous media, and black-body emission.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "lf/core/blackbody.h"
#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/vol_path_tracer.h"
#include "lf/local/local_executor.h"
#include "render_path.h"
#include "test_scenes.h"

namespace lf {
namespace {

// 5 standard errors: a correct renderer fails with probability below 1e-6 per check.
constexpr double kSigmas = 5.0;

RenderOutput RenderVol(const Scene& scene, uint64_t spp, uint64_t seed = 1) {
    absl::StatusOr<std::unique_ptr<EmbreeScene>> es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    const Camera camera(scene.camera, (*es)->origin());
    const VolPathTracer tracer(**es, -1);
    RenderSettings settings;
    settings.spp = spp;
    settings.seed = seed;
    settings.tile = 8;
    absl::StatusOr<RenderOutput> out = RenderImage(camera, tracer, settings);
    EXPECT_TRUE(out.ok()) << out.status();
    return *std::move(out);
}

// A closed box [lo, hi] with outward normals, of `material`, its inside medium `interior` and
// its outside vacuum.
void AddBox(Scene& scene, const Vec3d& lo, const Vec3d& hi, int material, int interior) {
    TriangleMesh m;
    m.material = material;
    m.media = {true, interior, -1};
    for (int i = 0; i < 8; ++i) {
        m.positions.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
    }
    // Each face's corners counter-clockwise seen from outside.
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        m.triangles.push_back({uint32_t(f[0]), uint32_t(f[1]), uint32_t(f[2])});
        m.triangles.push_back({uint32_t(f[0]), uint32_t(f[2]), uint32_t(f[3])});
    }
    scene.meshes.push_back(m);
}

int AddInterfaceMaterial(Scene& scene) {
    Material m;
    m.name = "boundary";
    m.type = Material::Type::kInterface;
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
}

Medium Homogeneous(const Rgb& sigma_a, const Rgb& sigma_s, float g = 0) {
    Medium m;
    m.name = "medium";
    m.sigma_a = sigma_a;
    m.sigma_s = sigma_s;
    m.g = g;
    return m;
}

// The same coefficients on a grid of density `density` everywhere over [lo, hi] (lattice
// spacing `voxel`, one lattice point of margin beyond the box, `pad` more zero points on
// the +x side).
Medium ConstantGrid(const Medium& base, const Vec3d& lo, const Vec3d& hi, double voxel,
                    float density, int pad = 0) {
    auto grid = std::make_shared<VolumeGrid>();
    grid->name = "test#density";
    const Vec3d extent = hi - lo;
    const int nx = int(std::ceil(extent.x / voxel)) + 3, ny = int(std::ceil(extent.y / voxel)) + 3,
              nz = int(std::ceil(extent.z / voxel)) + 3;
    grid->min = {-1, -1, -1};
    grid->size = {nx + pad, ny, nz};
    grid->values.assign(size_t(nx + pad) * ny * nz, 0.0f);
    for (int z = 0; z < nz; ++z) {
        for (int y = 0; y < ny; ++y) {
            for (int x = 0; x < nx; ++x) {
                grid->values[(size_t(z) * ny + y) * (nx + pad) + x] = density;
            }
        }
    }
    for (int r = 0; r < 3; ++r) {
        grid->index_to_world.m[r][r] = voxel;
        grid->index_to_world.m[r][3] = lo[r];
        grid->world_to_index.m[r][r] = 1 / voxel;
        grid->world_to_index.m[r][3] = -lo[r] / voxel;
    }
    Medium m = base;
    m.type = Medium::Type::kGrid;
    m.density = grid;
    return m;
}

// An emitter of radiance 1 behind a slab |z| < d/2 of `medium` bounded by interfaces, seen
// head-on through a 1-degree camera.
Scene SlabScene(const Medium& medium, double d, int size) {
    Scene scene;
    Material emitter;
    emitter.reflectance = Rgb(0);
    emitter.emission = Rgb(1);
    scene.materials.push_back(emitter);
    testing::AddQuad(scene, 0, {-5, -5, -2}, {5, -5, -2}, {5, 5, -2}, {-5, 5, -2});
    const int boundary = AddInterfaceMaterial(scene);
    scene.media.push_back(medium);
    AddBox(scene, {-2, -2, -d / 2}, {2, 2, d / 2}, boundary, 0);
    scene.camera = testing::SquareCamera({0, 0, 10}, {0, 0, 0}, {0, 1, 0}, 1, size);
    return scene;
}

TEST(VolPath, AbsorbingSlabFollowsBeersLawPerChannel) {
    const Rgb sigma_a(0.2f, 0.5f, 1.0f);
    const double d = 1;
    const Medium homogeneous = Homogeneous(sigma_a, Rgb(0));
    const Medium grid = ConstantGrid(homogeneous, {-2, -2, -d / 2}, {2, 2, d / 2}, 0.25, 1);
    for (const Medium& medium : {homogeneous, grid}) {
        SCOPED_TRACE(medium.type == Medium::Type::kGrid ? "grid (delta tracking)" : "homogeneous");
        const RenderOutput out = RenderVol(SlabScene(medium, d, 16), 4096);
        for (int c = 0; c < 3; ++c) {
            const char* names[3] = {"R", "G", "B"};
            const testing::MeanAndError m = testing::ChannelMean(out.image, names[c]);
            const double expected = std::exp(-sigma_a[c] * d);
            EXPECT_NEAR(m.mean, expected, 0.005 * expected) << names[c];
            EXPECT_NEAR(m.mean, expected, kSigmas * m.standard_error + 1e-4 * expected) << names[c];
        }
    }
}

// A sphere of radius 1 of `medium` (interface boundary) in a uniform environment of radiance
// 1, seen by an orthographic camera whose rays all pass within 0.01 of its centre.
Scene SphereInSky(const Medium& medium, bool orthographic, int size) {
    Scene scene;
    const int boundary = AddInterfaceMaterial(scene);
    scene.media.push_back(medium);
    Sphere s;
    s.material = boundary;
    s.center = {0, 0, 0};
    s.radius = 1;
    s.media = {true, 0, -1};
    scene.spheres.push_back(s);
    scene.environment = EnvironmentLight{};
    scene.camera = testing::SquareCamera({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 30, size);
    if (orthographic) {
        scene.camera.projection = CameraSpec::Projection::kOrthographic;
        scene.camera.half_height = 0.01;
    }
    return scene;
}

TEST(VolPath, NonAbsorbingSphereInAFurnaceIsInvisible) {
    for (float g : {0.0f, 0.7f, -0.4f}) {
        SCOPED_TRACE(g);
        const Scene scene = SphereInSky(Homogeneous(Rgb(0), Rgb(1, 3, 8), g), false, 16);
        const RenderOutput out = RenderVol(scene, 256);
        for (const char* c : {"R", "G", "B"}) {
            const testing::MeanAndError m = testing::ChannelMean(out.image, c);
            EXPECT_NEAR(m.mean, 1, kSigmas * m.standard_error + 1e-4) << c;
            EXPECT_NEAR(m.mean, 1, 0.01) << c;
        }
    }
}

TEST(VolPath, MurkyGlassOfIorOneInAFurnaceIsInvisible) {
    // A dielectric (IOR 1: no Fresnel reflection, no bending) holding a non-absorbing medium:
    // the medium inside a refracting surface, reached by transmission instead of an interface.
    Scene scene = SphereInSky(Homogeneous(Rgb(0), Rgb(2, 1, 4), 0.3f), false, 16);
    scene.materials[0].type = Material::Type::kDielectric;
    scene.materials[0].ior = 1;
    const RenderOutput out = RenderVol(scene, 256);
    for (const char* c : {"R", "G", "B"}) {
        const testing::MeanAndError m = testing::ChannelMean(out.image, c);
        EXPECT_NEAR(m.mean, 1, kSigmas * m.standard_error + 1e-4) << c;
    }
}

TEST(VolPath, CameraInsideAnAbsorbingMediumSeesTheSkyAttenuated) {
    // The camera at the centre of a sphere of radius 1 filled with an absorber: every ray
    // crosses 1 m of it to the sky of radiance 1, exactly (Beer's law needs no sampling).
    const Rgb sigma_a(0.3f, 1.0f, 2.5f);
    Scene scene = SphereInSky(Homogeneous(sigma_a, Rgb(0)), false, 8);
    scene.camera.position = {0, 0, 0};
    scene.camera.look_at = {0, 0, -1};
    scene.camera.fov_y_deg = 90;
    scene.camera_medium = 0;
    const RenderOutput out = RenderVol(scene, 4);
    for (int c = 0; c < 3; ++c) {
        const char* names[3] = {"R", "G", "B"};
        const std::vector<float>& v = *out.image.FindChannel(names[c]);
        for (float x : v) EXPECT_NEAR(x, std::exp(-sigma_a[c]), 1e-4) << names[c];
    }
}

TEST(VolPath, CameraInAnUnboundedAbsorberSeesNothing) {
    // The medium fills all space: a ray to the sky, escaping or a shadow ray, crosses an
    // infinite stretch of it. Exactly 0, whatever geometry happens to be near.
    Scene scene;
    Material floor;
    floor.reflectance = Rgb(0.8f);
    scene.materials.push_back(floor);
    testing::AddQuad(scene, 0, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2});
    scene.media.push_back(Homogeneous(Rgb(0.2f), Rgb(0)));
    scene.camera_medium = 0;
    scene.environment = EnvironmentLight{};
    DirectionalLight sun;
    sun.direction = Normalize(Vec3d(0.2, -1, 0.1));
    sun.irradiance = Rgb(3);
    scene.directional_lights.push_back(sun);
    scene.camera = testing::SquareCamera({0, 1, 3}, {0, 0, 0}, {0, 1, 0}, 60, 8);
    const RenderOutput out = RenderVol(scene, 16);
    for (const char* c : {"R", "G", "B"}) {
        for (float x : *out.image.FindChannel(c)) EXPECT_EQ(x, 0) << c;
    }
}

// The test's own analog random walk: the probability that light entering a sphere of radius
// 1 along a diameter leaves it again, with extinction sigma_t, single-scattering albedo
// `albedo` and Henyey-Greenstein's g (cos theta by the textbook inversion). By reciprocity
// and the uniform sky of radiance 1 this is the radiance seen along the diameter.
double EscapeProbability(double sigma_t, double albedo, double g, int walks) {
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> uni(0, 1);
    int escaped = 0;
    for (int w = 0; w < walks; ++w) {
        Vec3d p(0, 0, -1), d(0, 0, 1);
        for (;;) {
            p += d * (-std::log(1 - uni(rng)) / sigma_t);
            if (Dot(p, p) > 1) {
                ++escaped;
                break;
            }
            if (uni(rng) >= albedo) break;
            const double u = uni(rng);
            const double s = (1 - g * g) / (1 - g + 2 * g * u);
            const double cos_t = std::abs(g) < 1e-6 ? 1 - 2 * u : (1 + g * g - s * s) / (2 * g);
            const double sin_t = std::sqrt(std::max(0.0, 1 - cos_t * cos_t));
            const double phi = 2 * std::numbers::pi * uni(rng);
            // A frame around d.
            const Vec3d a = std::abs(d.x) > 0.9 ? Vec3d(0, 1, 0) : Vec3d(1, 0, 0);
            const Vec3d t1 = Normalize(Cross(d, a)), t2 = Cross(d, t1);
            d = Normalize(d * cos_t + t1 * (sin_t * std::cos(phi)) + t2 * (sin_t * std::sin(phi)));
        }
    }
    return double(escaped) / walks;
}

TEST(VolPath, HalfAlbedoSphereMatchesAnIndependentRandomWalk) {
    const double sigma_t = 2, albedo = 0.5, g = 0.3;
    const int walks = 1000000;
    const double reference = EscapeProbability(sigma_t, albedo, g, walks);
    const double reference_se = std::sqrt(reference * (1 - reference) / walks);
    const Medium medium =
        Homogeneous(Rgb(float(sigma_t * (1 - albedo))), Rgb(float(sigma_t * albedo)), float(g));
    const RenderOutput out = RenderVol(SphereInSky(medium, true, 16), 2048);
    for (const char* c : {"R", "G", "B"}) {
        const testing::MeanAndError m = testing::ChannelMean(out.image, c);
        EXPECT_NEAR(m.mean, reference,
                    kSigmas * std::hypot(m.standard_error, reference_se) + 1e-3 * reference)
            << c << " (rays within 0.01 of the centre: their paths are 2e-4 shorter at most)";
    }
}

void ExpectSameImage(const Image& a, const Image& b) {
    for (const char* c : {"R", "G", "B"}) {
        const auto blocks_a = testing::BlockStatistics(a, c, 4),
                   blocks_b = testing::BlockStatistics(b, c, 4);
        for (size_t i = 0; i < blocks_a.size(); ++i) {
            const double sigma = std::sqrt(blocks_a[i].second + blocks_b[i].second);
            EXPECT_NEAR(blocks_a[i].first, blocks_b[i].first, kSigmas * sigma + 1e-5)
                << "block " << i << " channel " << c;
        }
    }
}

// A box of chromatic scattering medium on a grey floor, lit by a sun through it and a sky.
Scene LitFogBox(const Medium& medium) {
    Scene scene;
    Material floor;
    floor.reflectance = Rgb(0.5f);
    scene.materials.push_back(floor);
    testing::AddQuad(scene, 0, {-4, -1, -4}, {-4, -1, 4}, {4, -1, 4}, {4, -1, -4});
    const int boundary = AddInterfaceMaterial(scene);
    scene.media.push_back(medium);
    AddBox(scene, {-1, -0.5, -1}, {1, 1, 1}, boundary, 0);
    DirectionalLight sun;
    sun.direction = Normalize(Vec3d(0.3, -1, 0.2));
    sun.irradiance = Rgb(2);
    scene.directional_lights.push_back(sun);
    scene.environment = EnvironmentLight{Rgb(0.3f)};
    scene.camera = testing::SquareCamera({0, 1.5, 5}, {0, 0, 0}, {0, 1, 0}, 40, 16);
    return scene;
}

TEST(VolPath, ConstantDensityGridRendersAsTheHomogeneousMedium) {
    const Medium homogeneous = Homogeneous(Rgb(0.1f, 0.2f, 0.3f), Rgb(0.8f, 0.5f, 1.5f), 0.5f);
    const Medium grid = ConstantGrid(homogeneous, {-1, -0.5, -1}, {1, 1, 1}, 0.1, 1);
    ExpectSameImage(RenderVol(LitFogBox(homogeneous), 512, 1).image,
                    RenderVol(LitFogBox(grid), 512, 2).image);
}

TEST(VolPath, EmptyVoxelsChangeNothing) {
    // Twice the density on half the lattice's points: the majorant grid's cells over the empty
    // part hold 0 and must be stepped over without bias.
    const Medium base = Homogeneous(Rgb(0.1f, 0.2f, 0.3f), Rgb(0.8f, 0.5f, 1.5f), 0.5f);
    const Medium tight = ConstantGrid(base, {-1, -0.5, -1}, {1, 1, 1}, 0.1, 1, 0);
    const Medium padded = ConstantGrid(base, {-1, -0.5, -1}, {1, 1, 1}, 0.1, 1, 40);
    ExpectSameImage(RenderVol(LitFogBox(tight), 512, 3).image,
                    RenderVol(LitFogBox(padded), 512, 4).image);
}

TEST(VolPath, OpticallyThickBlackBodyGridShowsPlancksLaw) {
    // Above 1900 K the Planckian locus lies inside Rec.709's gamut (BlackbodyRgb clips below).
    for (double kelvin : {2500.0, 4000.0, 6500.0}) {
        SCOPED_TRACE(kelvin);
        Medium m = ConstantGrid(Homogeneous(Rgb(40), Rgb(0)), {-2, -2, -1}, {2, 2, 1}, 0.25, 1);
        m.temperature = m.density;  // value 1 everywhere: kelvin = temperature_scale
        m.temperature_scale = kelvin;
        Scene scene = SlabScene(m, 2, 8);
        scene.materials[0].emission = Rgb(0);  // only the medium glows
        const RenderOutput out = RenderVol(scene, 64);
        // 80 optical depths: the slab shows Le itself, a black body at that temperature.
        double rgb[3];
        for (int c = 0; c < 3; ++c) {
            const char* names[3] = {"R", "G", "B"};
            rgb[c] = testing::ChannelMean(out.image, names[c]).mean;
        }
        // Linear Rec.709 (D65) to XYZ, IEC 61966-2-1.
        const double x = 0.4124564 * rgb[0] + 0.3575761 * rgb[1] + 0.1804375 * rgb[2];
        const double y = 0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2];
        const double z = 0.0193339 * rgb[0] + 0.1191920 * rgb[1] + 0.9503041 * rgb[2];
        const double luminance = 683 * y;
        EXPECT_NEAR(luminance, BlackbodyLuminance(kelvin), 0.01 * BlackbodyLuminance(kelvin));
        const Xyz planck = BlackbodyXyz(kelvin);
        const double sum = planck.x + planck.y + planck.z;
        EXPECT_NEAR(x / (x + y + z), planck.x / sum, 0.002);
        EXPECT_NEAR(y / (x + y + z), planck.y / sum, 0.002);
    }
}

// The scene files of tests/scenes/media (written by tools/media_scenes.py), through the loader
// and the method factory as `lightfarm render` takes them.
Scene LoadMediaScene(const std::string& name) {
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/media/" + name);
    EXPECT_TRUE(scene.ok()) << scene.status();
    return *std::move(scene);
}

TEST(VolPathScenes, SlabFileShowsBeersLaw) {
    const RenderOutput out = testing::RenderPath(LoadMediaScene("slab.json"), 16).out;
    const double expected[3] = {0.77880, 0.60653, 0.36788};  // exp(-(0.5, 1, 2) * 0.5)
    for (int c = 0; c < 3; ++c) {
        const char* names[3] = {"R", "G", "B"};
        EXPECT_NEAR(testing::ChannelMean(out.image, names[c]).mean, expected[c],
                    0.005 * expected[c])
            << names[c];
    }
}

TEST(VolPathScenes, HalfAlbedoFurnaceFileMatchesItsRandomWalkReference) {
    // tools/media_reference.py's analog random walk (numpy, 4 million walks): image mean
    // 0.67630 +- 0.00021.
    const RenderOutput out = testing::RenderPath(LoadMediaScene("furnace_albedo.json"), 512).out;
    for (const char* c : {"R", "G", "B"}) {
        const testing::MeanAndError m = testing::ChannelMean(out.image, c);
        EXPECT_NEAR(m.mean, 0.67630, kSigmas * std::hypot(m.standard_error, 0.00021)) << c;
    }
}

TEST(VolPathScenes, BlenderFireCacheRendersFiniteAndGlows) {
    Scene scene = LoadMediaScene("blender_fire.json");
    scene.camera.width = scene.camera.height = 16;
    const RenderOutput out = testing::RenderPath(scene, 16).out;
    EXPECT_EQ(out.stats.invalid_samples, 0u);
    // The flames' black body (up to ~2900 K) outshines the sky many times over.
    EXPECT_GT(testing::ChannelMean(out.image, "R").mean, 10 * 0.02);  // the sky: 0.02
}

}  // namespace
}  // namespace lf
