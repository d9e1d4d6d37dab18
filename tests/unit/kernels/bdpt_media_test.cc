// Bidirectional path tracing through participating media (lf/kernels/bdpt.h): a non-absorbing
// chromatic, anisotropic sphere of medium in a uniform sky is invisible (the furnace), and BDPT
// agrees block by block with the volumetric path tracer (the reference) on a Cornell box filled
// with fog (camera and lamp inside it), a scattering sphere under a spot light, a
// heterogeneous grid lit by an area light, and a lamp inside a fog ball (the light subpath
// must find the medium it starts in across the ball's interface).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "bdpt_render.h"
#include "bonferroni.h"
#include "lf/core/medium.h"
#include "test_scenes.h"

namespace lf {
namespace {

using testing::BdptFrame;
using testing::CompareWithPathTracer;
using testing::LoadSmall;
using testing::RenderBdpt;

Material InterfaceMaterial() { return {.name = "boundary", .type = Material::Type::kInterface}; }

Medium Fog(const Rgb& sigma_a, const Rgb& sigma_s, float g) {
    return {.name = "fog", .sigma_a = sigma_a, .sigma_s = sigma_s, .g = g};
}

// A ball of medium 0 (interface boundary, material `boundary`).
Sphere MediumBall(int boundary, const Vec3d& center, double radius) {
    Sphere s;
    s.name = "ball";
    s.material = boundary;
    s.center = center;
    s.radius = radius;
    s.media = {true, 0, -1};
    return s;
}

TEST(BdptMedia, NonAbsorbingChromaticSphereInAFurnaceIsInvisible) {
    Scene scene;
    scene.materials.push_back(InterfaceMaterial());
    scene.media.push_back(Fog(Rgb(0), Rgb(0.5f, 1.5f, 4), 0.6f));
    scene.spheres.push_back(MediumBall(0, {0, 0, 0}, 1));
    scene.environment = EnvironmentLight{};
    scene.camera = testing::SquareCamera({0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 35, 32);
    const BdptFrame f = RenderBdpt(scene, 128, -1);
    EXPECT_EQ(f.stats.invalid_samples, 0u);
    // Per channel, the frame mean and each 8 x 8 block's (every pixel sees the sky through
    // the ball or beside it: radiance 1), with errors from the pixels' A/B halves (blocks large
    // enough to hold many pixels that see the ball, whose halves differ).
    constexpr int kBlock = 8;
    const int bw = f.width / kBlock, bh = f.height / kBlock;
    const double z_max = testing::BonferroniZ(3 * bw * bh);
    for (int c = 0; c < 3; ++c) {
        double sum = 0, var = 0;
        for (int by = 0; by < bh; ++by) {
            for (int bx = 0; bx < bw; ++bx) {
                double block_sum = 0, block_var = 0;
                for (int y = by * kBlock; y < (by + 1) * kBlock; ++y) {
                    for (int x = bx * kBlock; x < (bx + 1) * kBlock; ++x) {
                        const size_t i = size_t(y * f.width + x);
                        const double a = f.half[0][i][c], b = f.half[1][i][c];
                        block_sum += (a + b) / 2;
                        block_var += (a - b) * (a - b) / 4;
                    }
                }
                const double n = kBlock * kBlock;
                // A zero spread only where no sample scattered: then every estimate is 1.
                EXPECT_LE(std::abs(block_sum / n - 1), z_max * std::sqrt(block_var) / n + 1e-4)
                    << "channel " << c << ", block " << bx << ", " << by;
                sum += block_sum;
                var += block_var;
            }
        }
        const double n = double(f.width) * f.height;
        const double mean = sum / n, error = std::sqrt(var) / n;
        std::printf("[bdpt media] furnace channel %d: %.5f +- %.5f\n", c, mean, error);
        EXPECT_NEAR(mean, 1, 5 * error + 1e-4) << "channel " << c;
        EXPECT_NEAR(mean, 1, 0.02) << "channel " << c;
    }
}

TEST(BdptMedia, MatchesThePathTracerInAFogFilledCornellBox) {
    CompareWithPathTracer("cornell fog", LoadSmall("media/cornell_fog.json", 32), 256, 512, 5);
}

TEST(BdptMedia, MatchesThePathTracerOnAScatteringSphereUnderASpotLight) {
    CompareWithPathTracer("spot sphere", LoadSmall("media/spot_sphere.json", 32), 256, 512, 6);
}

// A lattice over [lo, lo + n voxel]^3 whose density varies from 0 to 2 voxel by voxel in a
// pattern with no symmetry the majorant grid could hide.
std::shared_ptr<VolumeGrid> PatternGrid(const Vec3d& lo, double voxel, int n) {
    auto grid = std::make_shared<VolumeGrid>();
    grid->name = "pattern#density";
    grid->size = {n + 1, n + 1, n + 1};
    for (int z = 0; z <= n; ++z) {
        for (int y = 0; y <= n; ++y) {
            for (int x = 0; x <= n; ++x)
                grid->values.push_back(float((7 * x + 3 * y + 5 * z) % 11) / 5);
        }
    }
    for (int r = 0; r < 3; ++r) {
        grid->index_to_world.m[r][r] = voxel;
        grid->index_to_world.m[r][3] = lo[r];
        grid->world_to_index.m[r][r] = 1 / voxel;
        grid->world_to_index.m[r][3] = -lo[r] / voxel;
    }
    return grid;
}

// A grey room (inward box of half size 1) with a square lamp in its ceiling and a ball of
// `medium` (radius 0.6) in the middle; the camera inside the room, outside the ball.
Scene RoomWithBall(const Medium& medium, int size) {
    Scene scene;
    scene.materials.push_back({.name = "wall", .reflectance = Rgb(0.5f)});
    scene.materials.push_back({.name = "lamp", .reflectance = Rgb(0), .emission = Rgb(8, 6, 4)});
    scene.materials.push_back(InterfaceMaterial());
    testing::AddInwardBox(scene, {0, 0, 0}, 1, 0);
    testing::AddQuad(scene, 1, {-0.3, 0.99, -0.3}, {0.3, 0.99, -0.3}, {0.3, 0.99, 0.3},
                     {-0.3, 0.99, 0.3});  // facing down
    scene.media.push_back(medium);
    scene.spheres.push_back(MediumBall(2, {0, -0.2, 0}, 0.6));
    scene.camera = testing::SquareCamera({0, 0, 0.95}, {0, -0.2, 0}, {0, 1, 0}, 70, size);
    return scene;
}

TEST(BdptMedia, MatchesThePathTracerOnAHeterogeneousGridLitByAnAreaLight) {
    Medium smoke = Fog(Rgb(0.3f, 0.2f, 0.1f), Rgb(1.5f, 2.5f, 4), -0.3f);
    smoke.type = Medium::Type::kGrid;
    smoke.density = PatternGrid({-0.6, -0.8, -0.6}, 0.1, 12);
    CompareWithPathTracer("grid", RoomWithBall(smoke, 32), 256, 512, 5);
}

TEST(BdptMedia, FindsTheMediumOfALampInsideAFogBall) {
    // The ceiling lamp is off; a small glowing sphere without an interface of its own sits at
    // the ball's centre, in its fog. (A point light there would do too, but its next-event
    // estimates from medium vertices near it have infinite variance, which no z-test takes.)
    Scene scene = RoomWithBall(Fog(Rgb(0.2f), Rgb(1.5f, 1, 0.5f), 0.4f), 32);
    scene.materials[1].emission = Rgb(0);
    scene.materials.push_back({.name = "glow", .reflectance = Rgb(0), .emission = Rgb(20)});
    Sphere bulb;
    bulb.name = "bulb";
    bulb.material = int(scene.materials.size()) - 1;
    bulb.center = {0, -0.2, 0};
    bulb.radius = 0.1;
    scene.spheres.push_back(bulb);
    CompareWithPathTracer("lamp in fog", scene, 256, 512, 5);
}

TEST(BdptMedia, MatchesThePathTracerInFogThatFillsAllSpace) {
    // The camera's fog has no boundary: light from the sky and the sun crosses an infinite
    // stretch of it and never arrives, whichever strategy carries it; the lamp's light does.
    Scene scene;
    scene.materials.push_back({.name = "floor", .reflectance = Rgb(0.6f)});
    scene.materials.push_back({.name = "lamp", .reflectance = Rgb(0), .emission = Rgb(6, 5, 4)});
    testing::AddQuad(scene, 0, {-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2});
    testing::AddQuad(scene, 1, {-0.3, 1, -0.3}, {0.3, 1, -0.3}, {0.3, 1, 0.3},
                     {-0.3, 1, 0.3});  // facing down
    scene.media.push_back(Fog(Rgb(0.05f), Rgb(0.4f, 0.3f, 0.2f), 0.3f));
    scene.camera_medium = 0;
    scene.environment = EnvironmentLight{Rgb(1)};
    scene.directional_lights.push_back({Normalize(Vec3d(0.3, -1, 0.2)), Rgb(3), 0});
    scene.camera = testing::SquareCamera({0, 1.2, 2.5}, {0, 0.3, 0}, {0, 1, 0}, 60, 32);
    CompareWithPathTracer("fog everywhere", scene, 256, 512, 5);
}

}  // namespace
}  // namespace lf
