// Motion blur (issue 29): a sample's time in the shutter (Sampler::GetTime) places moving
// meshes (Embree's time steps), the camera and emitters sampled for next-event estimation.
// Streaks are measured against the projection of the distance travelled, energy against the
// still, methods against each other, and scenes where nothing moves keep their bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>

#include "bonferroni.h"
#include "lf/core/camera.h"
#include "lf/core/scene_animation.h"
#include "lf/job/splat_settings.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/lights.h"
#include "lf/kernels/path_tracer.h"
#include "lf/kernels/scene_motion.h"
#include "lf/local/local_executor.h"
#include "lf/local/method_factory.h"

namespace lf {
namespace {

using testing::BonferroniZ;

constexpr int kSize = 64;                       // pixels a side
constexpr double kPixelsPerUnit = kSize / 2.0;  // orthographic, half height 1
constexpr double kSide = 0.25;                  // the square's side: 8 pixels
constexpr double kTravel = 0.5;                 // during the shutter [0, 1] s: 16 pixels

// One node moving from x = -travel/2 to +travel/2 over [0, 1] s (linear keys), else still.
SceneAnimation OneMovingNode(double travel, double z) {
    SceneAnimation a;
    AnimationNode node;
    node.where = "nodes[0] \"mover\"";
    node.translation = {0, 0, z};
    a.nodes.push_back(node);
    if (travel != 0) {
        a.channels.push_back(
            {0, AnimationChannel::Path::kTranslation,
             Keyframes::Create(Interpolation::kLinear, KeyframeKind::kVector, 3, {0, 1},
                               {-travel / 2, 0, z, travel / 2, 0, z}, "test channel")
                 .value()});
    }
    return a;
}

// The square (mesh 0) driven by node 0, in the mesh's own space.
AnimatedMesh DrivenSquare(const TriangleMesh& square) {
    AnimatedMesh am;
    am.mesh = 0;
    am.node = 0;
    am.positions = square.positions;
    am.moves = true;
    return am;
}

// An emissive square (radiance 1, both faces) of side kSide in the plane z = 0 about its
// centre, seen by an orthographic camera looking down -z; `square_moves` or the camera moves.
struct MovingScene {
    Scene scene;
    SceneAnimation animation;
};

MovingScene SquareScene(bool square_moves, bool camera_moves) {
    MovingScene m;
    Material lamp;
    lamp.name = "lamp";
    lamp.emission = Rgb(1.0f);
    lamp.double_sided = true;
    lamp.two_sided_emission = true;
    lamp.reflectance = Rgb(0.0f);
    m.scene.materials.push_back(lamp);
    const double h = kSide / 2;
    TriangleMesh square;
    square.name = "square";
    square.positions = {{-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}};
    square.triangles = {{0, 1, 2}, {0, 2, 3}};
    m.scene.meshes.push_back(square);
    m.scene.camera.projection = CameraSpec::Projection::kOrthographic;
    m.scene.camera.position = {0, 0, 5};
    m.scene.camera.look_at = {0, 0, 0};
    m.scene.camera.half_height = 1;
    m.scene.camera.width = m.scene.camera.height = kSize;
    if (square_moves) {
        m.animation = OneMovingNode(kTravel, 0);
        m.animation.meshes.push_back(DrivenSquare(square));
    } else if (camera_moves) {
        m.animation = OneMovingNode(kTravel, 5);
        m.animation.camera_node = 0;
    }
    // The frame's instant is the middle of the shutter.
    EXPECT_TRUE(m.animation.PoseAt(0.5, m.scene).ok());
    return m;
}

struct Rendered {
    RenderOutput out;
    std::unique_ptr<EmbreeScene> embree;
};

Rendered RenderPathWithMotion(const Scene& scene, const SceneMotion& motion, uint64_t spp,
                              SamplerType sampler = SamplerType::kSobol) {
    auto es = EmbreeScene::Build(scene, nullptr, motion);
    EXPECT_TRUE(es.ok()) << es.status();
    const Camera camera(scene.camera, (*es)->origin(), (*es)->camera_motion());
    const PathTracer tracer(**es, 4);
    RenderSettings settings;
    settings.spp = spp;
    settings.seed = 3;
    settings.tile = 16;
    settings.sampler = sampler;
    return {RenderImage(camera, tracer, settings).value(), std::move(*es)};
}

Image RenderSplatWithMotion(const Scene& scene, const SceneMotion& motion, const char* method,
                            uint64_t spp, int max_depth = 4) {
    auto es = EmbreeScene::Build(scene, nullptr, motion);
    EXPECT_TRUE(es.ok()) << es.status();
    const Camera camera(scene.camera, (*es)->origin(), (*es)->camera_motion());
    SplatRenderSettings settings;
    settings.max_depth = max_depth;
    settings.seed = 5;
    auto renderer = MakeSplatRenderer(*FindMethod(method), **es, camera, settings);
    EXPECT_TRUE(renderer.ok()) << renderer.status();
    const SplatPlanSettings plan =
        SplatPlanSettingsOf(method, {scene.camera.width, scene.camera.height, spp, 16, 2}).value();
    RenderSettings local;
    local.threads = 2;
    return RenderSplatImage(camera, **renderer, plan, local).value().image;
}

// Mean and variance of the image's columns weighted by their brightness (channel average).
struct Spread {
    double sum = 0, mean = 0, variance = 0;
};
Spread HorizontalSpread(const Image& image) {
    Spread s;
    double sx = 0, sxx = 0;
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            const double v = image.Pixel(x, y).Average();
            const double cx = x + 0.5;
            s.sum += v;
            sx += v * cx;
            sxx += v * cx * cx;
        }
    }
    s.mean = sx / s.sum;
    s.variance = sxx / s.sum - s.mean * s.mean;
    return s;
}

// The image's sum and its standard error from the per-pixel A/B halves (Var of a pixel's
// mean = E[(A - B)^2] / 4).
struct Sum {
    double value = 0, error = 0;
};
Sum ImageSum(const Image& image) {
    Sum s;
    double var = 0;
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            const double a = image.Pixel(x, y, "A.").Average();
            const double b = image.Pixel(x, y, "B.").Average();
            s.value += (a + b) / 2;
            var += (a - b) * (a - b) / 4;
        }
    }
    s.error = std::sqrt(var);
    return s;
}

bool SameBits(const Image& a, const Image& b) {
    if (a.channels().size() != b.channels().size()) return false;
    for (const auto& [name, ca] : a.channels()) {
        const std::vector<float>* cb = b.FindChannel(name);
        if (cb == nullptr || ca.size() != cb->size() ||
            std::memcmp(ca.data(), cb->data(), ca.size() * sizeof(float)) != 0) {
            return false;
        }
    }
    return true;
}

// A streak of L pixels is the still image convolved with a box L wide: its variance grows by
// L^2 / 12 (variances of independent offsets add).
void ExpectStreak(const Image& still, const Image& blurred, const char* what) {
    const Spread s = HorizontalSpread(still), b = HorizontalSpread(blurred);
    const double length = kTravel * kPixelsPerUnit;
    const double expected = length * length / 12;
    std::printf("[motion] %s: still variance %.3f, blurred %.3f, added %.3f (L^2/12 = %.3f)\n",
                what, s.variance, b.variance, b.variance - s.variance, expected);
    EXPECT_NEAR(b.variance - s.variance, expected, 0.1 * expected) << what;
    // Centred where the still is: the shutter is centred on the frame's instant.
    EXPECT_NEAR(b.mean, s.mean, 0.25) << what;
}

TEST(MotionBlur, AMovingEmitterStreaksByTheProjectedDistance) {
    const MovingScene m = SquareScene(true, false);
    const Rendered still = RenderPathWithMotion(m.scene, {}, 64);
    const Rendered blurred = RenderPathWithMotion(m.scene, {&m.animation, 0, 1}, 64);
    EXPECT_EQ(blurred.embree->steps(), 2);  // straight-line motion
    EXPECT_TRUE(blurred.embree->Moves(0));
    ExpectStreak(still.out.image, blurred.out.image, "moving square");
}

TEST(MotionBlur, AMovingCameraStreaksAStillScene) {
    const MovingScene m = SquareScene(false, true);
    const Rendered still = RenderPathWithMotion(m.scene, {}, 64);
    const Rendered blurred = RenderPathWithMotion(m.scene, {&m.animation, 0, 1}, 64);
    EXPECT_EQ(blurred.embree->camera_motion().size(), 2u);
    EXPECT_FALSE(blurred.embree->Moves(0));
    ExpectStreak(still.out.image, blurred.out.image, "moving camera");
}

TEST(MotionBlur, AUniformlyMovingEmitterKeepsItsBrightness) {
    const MovingScene m = SquareScene(true, false);
    const Rendered still = RenderPathWithMotion(m.scene, {}, 32, SamplerType::kIndependent);
    const Rendered blurred =
        RenderPathWithMotion(m.scene, {&m.animation, 0, 1}, 32, SamplerType::kIndependent);
    const Sum s = ImageSum(still.out.image), b = ImageSum(blurred.out.image);
    const double se = std::hypot(s.error, b.error);
    std::printf("[motion] image sum: still %.3f +- %.3f, blurred %.3f +- %.3f\n", s.value, s.error,
                b.value, b.error);
    // The square covers 8 x 8 pixels of radiance 1.
    EXPECT_NEAR(s.value, 64, 1e-3);
    EXPECT_GT(se, 0);
    EXPECT_NEAR(b.value, s.value, 4 * se);
}

// Block means (channel average) of two renders agree within their A/B standard errors.
void ExpectSameBlocks(const Image& a, const Image& b, const char* what, int block = 8) {
    const int bw = a.width() / block, bh = a.height() / block;
    const double threshold = BonferroniZ(bw * bh);
    double worst = 0;
    for (int by = 0; by < bh; ++by) {
        for (int bx = 0; bx < bw; ++bx) {
            double m[2] = {}, v[2] = {};
            for (int y = by * block; y < (by + 1) * block; ++y) {
                for (int x = bx * block; x < (bx + 1) * block; ++x) {
                    for (int i = 0; i < 2; ++i) {
                        const Image& image = i == 0 ? a : b;
                        const double pa = image.Pixel(x, y, "A.").Average();
                        const double pb = image.Pixel(x, y, "B.").Average();
                        m[i] += (pa + pb) / 2;
                        v[i] += (pa - pb) * (pa - pb) / 4;
                    }
                }
            }
            const double se = std::sqrt(v[0] + v[1]);
            const double z = se > 0 ? (m[0] - m[1]) / se : (m[0] == m[1] ? 0 : 1e9);
            worst = std::max(worst, std::abs(z));
            EXPECT_LT(std::abs(z), threshold) << what << ": block " << bx << ", " << by << ": "
                                              << m[0] << " vs " << m[1] << " +- " << se;
        }
    }
    std::printf("[motion] %s: largest |z| %.2f of %d blocks (threshold %.2f)\n", what, worst,
                bw * bh, threshold);
}

// A diffuse wall behind the square (z = -0.3) and a perspective camera (light paths cannot
// reach an orthographic one) of `size` pixels a side.
void AddWallInPerspective(Scene& scene, int size) {
    Material wall;
    wall.name = "wall";
    wall.reflectance = Rgb(0.7f);
    scene.materials.push_back(wall);
    TriangleMesh back;
    back.name = "back";
    back.material = int(scene.materials.size()) - 1;
    back.positions = {{-2, -2, -0.3}, {2, -2, -0.3}, {2, 2, -0.3}, {-2, 2, -0.3}};
    back.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(back);
    scene.camera.projection = CameraSpec::Projection::kPerspective;
    scene.camera.position = {0, 0.3, 2};
    scene.camera.fov_y_deg = 40;
    scene.camera.width = scene.camera.height = size;
}

// A moving emissive square lighting a diffuse wall, seen in perspective: the path tracer, BDPT
// and the light tracer give one blurred image (the square's streak and the light it casts,
// both at the sample's time).
TEST(MotionBlur, MethodsAgreeOnABlurredScene) {
    MovingScene m = SquareScene(true, false);
    AddWallInPerspective(m.scene, 32);
    const SceneMotion motion{&m.animation, 0, 1};
    const Image path = RenderPathWithMotion(m.scene, motion, 256).out.image;
    ExpectSameBlocks(path, RenderSplatWithMotion(m.scene, motion, "bdpt", 128), "bdpt vs path");
    ExpectSameBlocks(path, RenderSplatWithMotion(m.scene, motion, "light", 128), "light vs path");
    // Not the still: the blur is there to see.
    const Image still = RenderPathWithMotion(m.scene, {}, 256).out.image;
    const double lit = HorizontalSpread(path).variance, sharp = HorizontalSpread(still).variance;
    EXPECT_GT(lit, sharp + 1);
}

// A point light moving over the wall (no emitter in view): the path tracer's next-event
// estimation (LightSampler) and the light tracer's emission (EmissionSampler) place it alike
// at each sample's time, and BDPT, which uses both, agrees with them.
TEST(MotionBlur, AMovingPointLightLightsTheSameForEveryMethod) {
    Scene scene;
    AddWallInPerspective(scene, 32);
    // A floor, so that light also arrives after a bounce (photons, light subpaths).
    TriangleMesh floor;
    floor.name = "floor";
    floor.material = 0;
    floor.positions = {{-2, -0.4, -0.3}, {2, -0.4, -0.3}, {2, -0.4, 2}, {-2, -0.4, 2}};
    floor.triangles = {{0, 2, 1}, {0, 3, 2}};
    scene.meshes.push_back(floor);
    scene.point_lights.push_back({{0, 0, 0.2}, Rgb(2.0f)});
    SceneAnimation animation = OneMovingNode(1.0, 0.2);
    animation.lights.push_back({AnimatedLight::Kind::kPoint, 0, 0, true});
    ASSERT_TRUE(animation.PoseAt(0.5, scene).ok());
    const SceneMotion motion{&animation, 0, 1};
    const Image path = RenderPathWithMotion(scene, motion, 128).out.image;
    ExpectSameBlocks(path, RenderSplatWithMotion(scene, motion, "light", 64), "point: light");
    ExpectSameBlocks(path, RenderSplatWithMotion(scene, motion, "bdpt", 64), "point: bdpt");
    // Photon mapping: its direct light is next-event estimation at each pass's time.
    ExpectSameBlocks(path, RenderSplatWithMotion(scene, motion, "ppm", 64), "point: ppm");
    // The light spreads: its pool on the wall is wider than the still's.
    const Image still = RenderPathWithMotion(scene, {}, 128).out.image;
    EXPECT_GT(HorizontalSpread(path).variance, HorizontalSpread(still).variance + 1);
}

// A square turning a quarter turn about +y over the shutter (rotation keys, so 9 steps) and
// emitting: a ray at time t hits it where its pose at t is, to within the steps' chord error,
// and a light sample of it at time t lies on the surface a ray of that time hits.
TEST(MotionBlur, ARotatingEmitterIsWhereItsPoseIsAndItsLightSamplesAgree) {
    MovingScene m = SquareScene(false, false);
    m.animation = OneMovingNode(0, 0);
    const double s = std::sqrt(0.5);
    m.animation.channels.push_back(
        {0, AnimationChannel::Path::kRotation,
         Keyframes::Create(Interpolation::kLinear, KeyframeKind::kRotation, 4, {0, 1},
                           {0, 0, 0, 1, 0, s, 0, s}, "test rotation")
             .value()});
    m.animation.meshes.push_back(DrivenSquare(m.scene.meshes[0]));
    ASSERT_TRUE(m.animation.PoseAt(0.5, m.scene).ok());
    const SceneMotion motion{&m.animation, 0, 1};
    EXPECT_EQ(MotionSteps(motion), kCurvedMotionSteps);
    auto es = EmbreeScene::Build(m.scene, nullptr, motion);
    ASSERT_TRUE(es.ok()) << es.status();
    ASSERT_TRUE((*es)->Moves(0));
    const LightSampler lights(**es);
    for (const float t : {0.0f, 0.1f, 0.3f, 0.5f, 0.77f}) {
        // The square's plane at t: through the origin, normal (sin a, 0, cos a), a = t pi/2.
        const double a = t * std::numbers::pi / 2;
        const Vec3 normal(float(std::sin(a)), 0, float(std::cos(a)));
        const Vec3 o = Vec3(Vec3d(0.02, 0.01, 5) - (*es)->origin());
        const Ray ray{o, Vec3(0, 0, -1), std::numeric_limits<float>::infinity(), t};
        const std::optional<SurfaceHit> hit = (*es)->Intersect(ray);
        ASSERT_TRUE(hit) << t;
        EXPECT_EQ(hit->time, t);
        const Vec3 world = hit->p + Vec3((*es)->origin());
        // 9 steps: the chord of an eighth of the quarter turn at radius 0.02 is far below 1e-4.
        EXPECT_NEAR(Dot(world, normal), 0, 1e-4) << t;
        // A light sample seen from in front of the square at time t, and the ray of that time
        // towards it: it hits the sampled point on the emitter.
        const Vec3 ref = Vec3(Vec3d(0.3 * std::sin(a), 0.05, 0.3 * std::cos(a)) - (*es)->origin());
        for (const float u : {0.2f, 0.6f}) {
            const std::optional<LightSample> ls =
                lights.Sample(ref, Vec3(0, 0, 0), 0.5f, {u, 0.4f}, t);
            ASSERT_TRUE(ls) << t;
            EXPECT_EQ(ls->point.time, t);
            const Vec3 sampled = ls->point.p + Vec3((*es)->origin());
            EXPECT_NEAR(Dot(sampled, normal), 0, 1e-4) << t;
            const std::optional<SurfaceHit> towards =
                (*es)->Intersect(Ray{ref, ls->wi, std::numeric_limits<float>::infinity(), t});
            ASSERT_TRUE(towards) << t;
            EXPECT_LT(Length(towards->p - ls->point.p), 1e-4f) << t;
            EXPECT_NEAR(lights.Pdf(ref, Vec3(0, 0, 0), *towards), ls->pdf, 1e-3f * ls->pdf) << t;
        }
    }
}

// A morph target (a weights channel: deformation, so 9 steps) lifting one corner of the
// square: a ray at time t hits the surface of that time's pose. The lift is linear in the
// weight, so the steps' interpolation is exact.
TEST(MotionBlur, AMorphedMeshIsHitWhereItsPoseIs) {
    MovingScene m = SquareScene(false, false);
    m.animation = OneMovingNode(0, 0);
    m.animation.channels.push_back({0, AnimationChannel::Path::kWeights,
                                    Keyframes::Create(Interpolation::kLinear, KeyframeKind::kVector,
                                                      1, {0, 1}, {0, 1}, "test weights")
                                        .value()});
    AnimatedMesh am = DrivenSquare(m.scene.meshes[0]);
    am.targets.push_back({{{0, 0, 0}, {0, 0, 0}, {0, 0, 0.5}, {0, 0, 0}}, {}, {}});
    am.weights = {0};
    m.animation.meshes.push_back(am);
    ASSERT_TRUE(m.animation.PoseAt(0.5, m.scene).ok());
    const SceneMotion motion{&m.animation, 0, 1};
    EXPECT_EQ(MotionSteps(motion), kCurvedMotionSteps);
    auto es = EmbreeScene::Build(m.scene, nullptr, motion);
    ASSERT_TRUE(es.ok()) << es.status();
    for (const float t : {0.0f, 0.2f, 0.55f, 1.0f}) {
        // (0.1, 0.05) has barycentric 0.7 on the lifted corner of triangle 0.
        const Vec3 o = Vec3(Vec3d(0.1, 0.05, 5) - (*es)->origin());
        const std::optional<SurfaceHit> hit =
            (*es)->Intersect(Ray{o, Vec3(0, 0, -1), std::numeric_limits<float>::infinity(), t});
        ASSERT_TRUE(hit) << t;
        EXPECT_NEAR(hit->p.z + (*es)->origin().z, 0.35 * t, 1e-5) << t;
    }
}

// The instant the scene was posed at: a closed shutter, or an open one over which nothing
// moves, renders the still's bits, by the path tracer and a splatting method.
TEST(MotionBlur, WhenNothingMovesTheShutterKeepsTheStillsBits) {
    MovingScene m = SquareScene(true, false);
    AddWallInPerspective(m.scene, 24);
    SceneAnimation still_animation = OneMovingNode(0, 0);  // no channel
    still_animation.meshes = m.animation.meshes;
    still_animation.meshes[0].moves = false;
    ASSERT_FALSE(still_animation.Moves());
    const SceneMotion instant{&m.animation, 0.5, 0.5}, nothing_moves{&still_animation, 0, 1};
    const Image path = RenderPathWithMotion(m.scene, {}, 8).out.image;
    const Image bdpt = RenderSplatWithMotion(m.scene, {}, "bdpt", 8);
    for (const SceneMotion& motion : {instant, nothing_moves}) {
        EXPECT_FALSE(motion.Blurs());
        EXPECT_TRUE(SameBits(path, RenderPathWithMotion(m.scene, motion, 8).out.image));
        EXPECT_TRUE(SameBits(bdpt, RenderSplatWithMotion(m.scene, motion, "bdpt", 8)));
    }
}

TEST(MotionBlur, TheTimeIsADimensionOfItsOwn) {
    for (const SamplerType type : {SamplerType::kIndependent, SamplerType::kSobol}) {
        Sampler a(7, 3, 4, 5, type), b(7, 3, 4, 5, type);
        const float time = b.GetTime();
        EXPECT_GE(time, 0.0f);
        EXPECT_LT(time, 1.0f);
        for (int i = 0; i < 8; ++i) {
            const Vec2 ua = a.Get2D(), ub = b.Get2D();
            EXPECT_EQ(ua.x, ub.x);
            EXPECT_EQ(ua.y, ub.y);
        }
    }
    // Sobol stratifies the times of a pixel's samples: each of 16 strata of [0, 1) gets one of
    // the first 16 even (half A) samples.
    int hits[16] = {};
    for (uint64_t s = 0; s < 32; s += 2) {
        ++hits[int(Sampler(9, 1, 2, s, SamplerType::kSobol).GetTime() * 16)];
    }
    for (int h : hits) EXPECT_EQ(h, 1);
}

// Two poses are exact only for a straight path at constant speed over the shutter: a key inside
// it (a bounce) or a CUBICSPLINE path takes the curved rule's steps.
TEST(MotionBlur, TwoStepsOnlyForAStraightPathOverTheShutter) {
    const auto steps = [](Interpolation interpolation, std::vector<double> times,
                          std::vector<double> values, double open, double close) {
        SceneAnimation a = OneMovingNode(0, 0);
        a.channels.push_back({0, AnimationChannel::Path::kTranslation,
                              Keyframes::Create(interpolation, KeyframeKind::kVector, 3,
                                                std::move(times), std::move(values), "test")
                                  .value()});
        TriangleMesh square;
        square.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        a.meshes.push_back(DrivenSquare(square));
        return MotionSteps(SceneMotion{&a, open, close});
    };
    const std::vector<double> bounce = {0, 0, 0, 0, 1, 0, 0, 0, 0};  // up and down again
    EXPECT_EQ(steps(Interpolation::kLinear, {0, 0.5, 1}, bounce, 0.1, 0.4), 2);
    EXPECT_EQ(steps(Interpolation::kLinear, {0, 0.5, 1}, bounce, 0.4, 0.6), kCurvedMotionSteps);
    EXPECT_EQ(steps(Interpolation::kStep, {0, 0.5, 1}, bounce, 0.6, 0.9), 2);
    EXPECT_EQ(steps(Interpolation::kStep, {0, 0.5, 1}, bounce, 0.4, 0.6), kCurvedMotionSteps);
    // CUBICSPLINE: in-tangent, value, out-tangent per key.
    EXPECT_EQ(steps(Interpolation::kCubicSpline, {0, 1},
                    {0, 1, 0, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1, 0, 0, 0, -1, 0}, 0.1, 0.4),
              kCurvedMotionSteps);
}

// What the steps do not move yet is refused, not rendered sharp beside blurred meshes.
// An emissive analytic sphere (radius 1 at unit radiance, in the plane z = 0) of kSide diameter
// driven by node 0, as SquareScene's square.
MovingScene SphereScene() {
    MovingScene m = SquareScene(false, false);
    m.scene.meshes.clear();
    m.scene.materials[0].two_sided_emission = false;
    m.scene.spheres.push_back({.material = 0, .center = {0, 0, 0}, .radius = kSide / 2});
    m.animation = OneMovingNode(kTravel, 0);
    m.animation.spheres.push_back(
        {.sphere = 0, .node = 0, .center = {0, 0, 0}, .radius = kSide / 2, .moves = true});
    EXPECT_TRUE(m.animation.PoseAt(0.5, m.scene).ok());
    return m;
}

// Embree moves the sphere by its time steps, and the centre the kernels shade and sample at is
// the one a ray of that time hits: the streak has the analytic length, and lighting a wall the
// path tracer (cone sampling about the centre at the sample's time), BDPT and the light tracer
// (emission from the sphere at the path's time) agree.
TEST(MotionBlur, AMovingAnalyticSphereStreaksAndLightsAlikeForEveryMethod) {
    MovingScene m = SphereScene();
    const Rendered still = RenderPathWithMotion(m.scene, {}, 64);
    const Rendered blurred = RenderPathWithMotion(m.scene, {&m.animation, 0, 1}, 64);
    EXPECT_EQ(blurred.embree->steps(), 2);
    EXPECT_EQ(blurred.embree->SphereCenter(0, 0).x, float(-kTravel / 2));
    EXPECT_EQ(blurred.embree->SphereCenter(0, 1).x, float(kTravel / 2));
    ExpectStreak(still.out.image, blurred.out.image, "moving sphere");

    AddWallInPerspective(m.scene, 32);
    const SceneMotion motion{&m.animation, 0, 1};
    const Image path = RenderPathWithMotion(m.scene, motion, 256).out.image;
    ExpectSameBlocks(path, RenderSplatWithMotion(m.scene, motion, "bdpt", 128), "sphere: bdpt");
    ExpectSameBlocks(path, RenderSplatWithMotion(m.scene, motion, "light", 128), "sphere: light");
}

TEST(MotionBlur, AGrowingSphereOrTurningDirectionalLightUnderAShutterIsRefusedNamingIt) {
    MovingScene m = SphereScene();
    m.animation.channels.push_back({0, AnimationChannel::Path::kScale,
                                    Keyframes::Create(Interpolation::kLinear, KeyframeKind::kVector,
                                                      3, {0, 1}, {1, 1, 1, 2, 2, 2}, "test scale")
                                        .value()});
    auto refused = EmbreeScene::Build(m.scene, nullptr, SceneMotion{&m.animation, 0, 1});
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kUnimplemented);
    EXPECT_NE(refused.status().message().find(
                  "spheres[0] (nodes[0] \"mover\") changes size during the shutter"),
              std::string_view::npos)
        << refused.status();
    // The instant (a still of that frame) renders it.
    EXPECT_TRUE(EmbreeScene::Build(m.scene, nullptr, SceneMotion{&m.animation, 0.5, 0.5}).ok());
    m = SquareScene(true, false);
    m.scene.directional_lights.push_back({.direction = {0, -1, 0}, .irradiance = Rgb(1.0f)});
    m.animation.lights.push_back(
        {.kind = AnimatedLight::Kind::kDirectional, .index = 0, .node = 0, .moves = true});
    refused = EmbreeScene::Build(m.scene, nullptr, SceneMotion{&m.animation, 0, 1});
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.status().message().find("directional light 0"), std::string_view::npos)
        << refused.status();
}

}  // namespace
}  // namespace lf
