// JSON shapes and cameras with keyframed transforms (docs/scene-format.md, "Keyframes"):
// posed where the formulas say, STEP against LINEAR, and bad keyframes named by their path.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "lf/core/scene_animation.h"
#include "lf/core/scene_loader.h"

namespace lf {
namespace {

using ::testing::HasSubstr;
using Json = nlohmann::json;

constexpr double kPi = std::numbers::pi;

void ExpectNear(const Vec3d& a, const Vec3d& b, double tolerance = 1e-9) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// A scene of `shapes` (a grey material "grey", an emissive "glow") seen by `camera`.
absl::StatusOr<Scene> Load(const Json& shapes, const Json& camera = Json()) {
    Json json = {
        {"camera", camera.is_null() ? Json{{"position", {0, 0, 10}},
                                           {"look_at", {0, 0, 0}},
                                           {"fov_y_deg", 40},
                                           {"resolution", {64, 48}}}
                                    : camera},
        {"materials",
         {{"grey", {{"type", "lambert"}, {"reflectance", {0.5, 0.5, 0.5}}}},
          {"glow", {{"type", "lambert"}, {"reflectance", {0, 0, 0}}, {"emission", {1, 1, 1}}}}}},
        {"shapes", shapes}};
    return ParseScene(json.dump(), "shot.json",
                      [](const std::string& name) -> absl::StatusOr<std::string> {
                          return absl::NotFoundError(name);
                      });
}

std::string LoadError(const Json& shapes, const Json& camera = Json()) {
    absl::StatusOr<Scene> scene = Load(shapes, camera);
    EXPECT_FALSE(scene.ok());
    EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(scene.status().message());
}

// A ball of radius 0.5 at (0, 1, 0) of its own space, moved from (1, 2, 3) to (5, 2, 3),
// turned 0 to 90 degrees about +z and scaled 1 to 3 over 2 s.
Json Ball(const std::string& interpolation) {
    return {{"type", "sphere"},
            {"name", "ball"},
            {"material", "glow"},
            {"center", {0, 1, 0}},
            {"radius", 0.5},
            {"transform",
             {{"interpolation", interpolation},
              {"keyframes",
               {{{"time", 0},
                 {"translate", {1, 2, 3}},
                 {"rotate", {{"axis", {0, 0, 1}}, {"angle_deg", 0}}},
                 {"scale", 1}},
                {{"time", 2},
                 {"translate", {5, 2, 3}},
                 {"rotate", {{"axis", {0, 0, 1}}, {"angle_deg", 90}}},
                 {"scale", 3}}}}}}};
}

TEST(SceneKeyframes, ASphereIsPosedWhereTheFormulaSays) {
    absl::StatusOr<Scene> scene = Load(Json::array({Ball("LINEAR")}));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    EXPECT_TRUE(scene->animation->Moves());
    ASSERT_EQ(scene->animation->spheres.size(), 1u);
    EXPECT_TRUE(scene->animation->spheres[0].moves);
    EXPECT_EQ(scene->animation->Start(), 0);
    EXPECT_EQ(scene->animation->End(), 2);
    // A still shows the first keyframe.
    ExpectNear(scene->spheres[0].center, Vec3d(1, 3, 3));
    EXPECT_EQ(scene->spheres[0].radius, 0.5);
    for (const double t : {-1.0, 0.5, 1.0, 2.0, 7.0}) {
        SCOPED_TRACE(t);
        ASSERT_TRUE(scene->animation->PoseAt(t, *scene).ok());
        // p' = T(t) R(t) S(t) p, each part linear in the clamped time (the rotation's angle
        // too: slerp about one axis turns at a constant rate).
        const double s = std::clamp(t, 0.0, 2.0) / 2;
        const double scale = 1 + 2 * s, angle = s * kPi / 2;
        const Vec3d expected =
            Vec3d(1 + 4 * s, 2, 3) + scale * Vec3d(-std::sin(angle), std::cos(angle), 0);
        ExpectNear(scene->spheres[0].center, expected);
        EXPECT_NEAR(scene->spheres[0].radius, 0.5 * scale, 1e-12);
    }
}

TEST(SceneKeyframes, StepHoldsEachKeyUntilTheNext) {
    absl::StatusOr<Scene> scene = Load(Json::array({Ball("STEP")}));
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_TRUE(scene->animation->PoseAt(1.999, *scene).ok());
    ExpectNear(scene->spheres[0].center, Vec3d(1, 3, 3));
    EXPECT_NEAR(scene->spheres[0].radius, 0.5, 1e-12);
    ASSERT_TRUE(scene->animation->PoseAt(2, *scene).ok());
    ExpectNear(scene->spheres[0].center, Vec3d(5 - 3, 2, 3));
    EXPECT_NEAR(scene->spheres[0].radius, 1.5, 1e-12);
}

TEST(SceneKeyframes, AQuadAndTheCameraMoveAndStillShapesStay) {
    const Json shapes = {
        {{"type", "quad"},
         {"material", "grey"},
         {"vertices", {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
         {"transform",
          {{"keyframes",
            {{{"time", 1}, {"translate", {0, 0, 0}}}, {{"time", 3}, {"translate", {0, 4, 0}}}}}}}},
        {{"type", "sphere"}, {"material", "glow"}, {"center", {0, 0, -3}}, {"radius", 1}}};
    const Json camera = {
        {"position", {0, 0, 5}},
        {"look_at", {0, 0, 0}},
        {"fov_y_deg", 40},
        {"resolution", {64, 48}},
        {"transform",
         {{"keyframes",
           {{{"time", 0}, {"rotate", {{"axis", {0, 1, 0}}, {"angle_deg", 0}}}},
            {{"time", 1}, {"rotate", {{"axis", {0, 1, 0}}, {"angle_deg", 90}}}}}}}}};
    absl::StatusOr<Scene> scene = Load(shapes, camera);
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    EXPECT_EQ(scene->animation->spheres.size(), 0u);  // the ball has no keyframes
    ASSERT_EQ(scene->animation->meshes.size(), 1u);
    ASSERT_TRUE(scene->animation->PoseAt(2, *scene).ok());
    ExpectNear(scene->meshes[0].positions[2], Vec3d(1, 3, 0));
    ExpectNear(scene->spheres[0].center, Vec3d(0, 0, -3));
    // A quarter turn about +y takes (0, 0, 5) to (5, 0, 0), looking down -x.
    ExpectNear(scene->camera.position, Vec3d(5, 0, 0));
    ExpectNear(Normalize(scene->camera.look_at - scene->camera.position), Vec3d(-1, 0, 0));
    ExpectNear(Normalize(scene->camera.up), Vec3d(0, 1, 0));
    EXPECT_EQ(scene->camera.width, 64);
    ASSERT_TRUE(scene->animation->PoseAt(0.5, *scene).ok());
    ExpectNear(scene->camera.position, 5.0 * Vec3d(std::sin(kPi / 4), 0, std::cos(kPi / 4)));
    ExpectNear(scene->meshes[0].positions[2], Vec3d(1, 1, 0));
}

TEST(SceneKeyframes, TheShotScenesMoveTheBallAndTheCamera) {
    // tests/scenes/shot (README.md there): the ball at x = -2 + 4 t, the camera at x = t.
    for (const char* name : {"moving_ball.json", "moving_ball_camera.json"}) {
        SCOPED_TRACE(name);
        absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/shots/" + name);
        ASSERT_TRUE(scene.ok()) << scene.status();
        ASSERT_NE(scene->animation, nullptr);
        const bool camera_moves = std::string(name) == "moving_ball_camera.json";
        for (const int frame : {1, 12, 24}) {
            const double t = frame / 24.0;
            ASSERT_TRUE(scene->animation->PoseAt(t, *scene).ok());
            ExpectNear(scene->spheres[0].center, Vec3d(-2 + 4 * t, 0, 0));
            ExpectNear(scene->camera.position, Vec3d(camera_moves ? t : 0, 0, 10));
            ExpectNear(Normalize(scene->camera.look_at - scene->camera.position), Vec3d(0, 0, -1));
        }
    }
}

TEST(SceneKeyframes, BadKeyframesAreRefusedNamingTheirPath) {
    const auto ball = [](const Json& transform) {
        Json b = Ball("LINEAR");
        b["transform"] = transform;
        return Json::array({b});
    };
    const auto key = [](double time, double x) {
        return Json{{"time", time}, {"translate", {x, 0, 0}}};
    };
    EXPECT_EQ(LoadError(ball({{"keyframes", {key(0, 0), key(1, 1), key(1, 2)}}})),
              "shot.json: shapes[0].transform.keyframes[2].time: 1 s is not after "
              "keyframes[1].time (1 s): times must increase");
    EXPECT_EQ(LoadError(ball({{"keyframes", {key(1, 0), key(0, 1)}}})),
              "shot.json: shapes[0].transform.keyframes[1].time: 0 s is not after "
              "keyframes[0].time (1 s): times must increase");
    EXPECT_EQ(LoadError(ball({{"keyframes", {key(0, 0), {{"time", 1}}}}})),
              "shot.json: shapes[0].transform.keyframes[1]: lacks \"translate\", which "
              "keyframes[0] gives: every keyframe gives the same parts");
    EXPECT_EQ(LoadError(ball({{"keyframes", Json::array()}})),
              "shot.json: shapes[0].transform.keyframes: no keyframes; give at least one");
    EXPECT_EQ(LoadError(ball({{"keyframes", {key(0, 0)}}, {"interpolation", "CUBICSPLINE"}})),
              "shot.json: shapes[0].transform.interpolation: unknown interpolation "
              "\"CUBICSPLINE\"; expected LINEAR or STEP");
    EXPECT_EQ(LoadError(ball({{"keyframes", {{{"time", 0}, {"scale", {1, 2, 1}}}}}})),
              "shot.json: shapes[0].transform.keyframes[0].scale: scales unevenly; a sphere "
              "takes a uniform scale only (one number)");
    EXPECT_EQ(LoadError(ball({{"scale", {1, 2, 1}}})),
              "shot.json: shapes[0].transform: scales unevenly; a sphere takes a uniform scale "
              "only (one number)");
    EXPECT_EQ(LoadError(ball({{"keyframes", {{{"time", 0}, {"scale", 0}}}}})),
              "shot.json: shapes[0].transform.keyframes[0].scale: must be above 0: a keyframed "
              "transform neither flattens nor mirrors");
    EXPECT_EQ(LoadError(ball({{"keyframes", {{{"time", "0"}}}}})),
              "shot.json: shapes[0].transform.keyframes[0].time: expected a number, got string "
              "\"0\"");
    EXPECT_THAT(
        LoadError(
            {{{"type", "gltf"}, {"file", "car.glb"}, {"transform", {{"keyframes", {key(0, 0)}}}}}}),
        HasSubstr("shapes[0].transform: a glTF's transform is fixed; animate its nodes in the "
                  "glTF itself"));
    const Json camera = {{"position", {0, 0, 5}},
                         {"look_at", {0, 0, 0}},
                         {"fov_y_deg", 40},
                         {"resolution", {64, 48}},
                         {"transform", {{"keyframes", {{{"time", 0}, {"scale", 2}}}}}}};
    EXPECT_EQ(LoadError(Json::array({Ball("LINEAR")}), camera),
              "shot.json: camera.transform.keyframes[0].scale: a camera's keyframes may only "
              "rotate and translate");
}

}  // namespace
}  // namespace lf
