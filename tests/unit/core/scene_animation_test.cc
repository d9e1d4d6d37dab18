#include "lf/core/scene_animation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "gltf_files.h"
#include "lf/core/scene_loader.h"
#include "scene_log.h"

namespace lf {
namespace {

using testing::GltfBuilder;
using ::testing::HasSubstr;
using Json = nlohmann::json;

constexpr double kPi = std::numbers::pi;

// A glTF made in memory (its buffer a data URI); "auto" frames files without a camera.
absl::StatusOr<Scene> Load(const GltfBuilder& b, const std::string& camera = "") {
    SceneOptions options;
    options.camera = camera;
    return ParseScene(
        b.GltfEmbedded(), "anim.gltf",
        [](const std::string& name) -> absl::StatusOr<std::string> {
            return absl::NotFoundError(name);
        },
        options);
}

void ExpectNear(const Vec3d& a, const Vec3d& b, double tolerance = 1e-6) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

Vec3d RotateY(const Vec3d& v, double angle) {
    return {v.x * std::cos(angle) + v.z * std::sin(angle), v.y,
            -v.x * std::sin(angle) + v.z * std::cos(angle)};
}

Vec3d RotateZ(const Vec3d& v, double angle) {
    return {v.x * std::cos(angle) - v.y * std::sin(angle),
            v.x * std::sin(angle) + v.y * std::cos(angle), v.z};
}

// One animation of LINEAR samplers, each (input, output) driving `path` of `node`.
struct ChannelSpec {
    int node;
    std::string path;
    int input, output;
    std::string interpolation = "LINEAR";
};
void Animate(GltfBuilder& b, const std::vector<ChannelSpec>& channels) {
    Json animation = {{"name", "Action"}, {"samplers", Json::array()}, {"channels", Json::array()}};
    for (const ChannelSpec& c : channels) {
        animation["channels"].push_back({{"sampler", animation["samplers"].size()},
                                         {"target", {{"node", c.node}, {"path", c.path}}}});
        animation["samplers"].push_back(
            {{"input", c.input}, {"output", c.output}, {"interpolation", c.interpolation}});
    }
    b.json()["animations"].push_back(animation);
}

int Triangle(GltfBuilder& b) {
    const int positions = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}, {{0, 1, 0}}});
    return b.AddMesh("tri", {{"POSITION", positions}}, -1, -1);
}

// A parent moving from (0, 0, 0) to (4, 0, 0) and turning a quarter about +y over 2 s, over a
// triangle at (1, 0, 0), a camera at (0, 0, 5) and a point and a spot light at (0, 2, 0).
GltfBuilder MovingParent() {
    GltfBuilder b;
    Json& j = b.json();
    const int mesh = Triangle(b);
    j["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}};
    j["extensionsUsed"] = {"KHR_lights_punctual"};
    j["extensions"]["KHR_lights_punctual"]["lights"] = {
        {{"type", "point"}, {"intensity", 683}},
        {{"type", "spot"}, {"intensity", 683}, {"spot", {{"outerConeAngle", 0.5}}}}};
    const int child = b.AddNode({{"name", "Tri"}, {"mesh", mesh}, {"translation", {1, 0, 0}}});
    const int camera = b.AddNode({{"name", "Cam"}, {"camera", 0}, {"translation", {0, 0, 5}}});
    const int lamp = b.AddNode({{"name", "Lamp"},
                                {"translation", {0, 2, 0}},
                                {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    const int spot = b.AddNode({{"name", "Spot"},
                                {"translation", {0, 2, 0}},
                                {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
    const int parent = b.AddNode({{"name", "Mover"}, {"children", {child, camera, lamp, spot}}});
    const int still = b.AddNode({{"name", "Still"}, {"mesh", mesh}, {"translation", {0, -3, 0}}});
    j["scenes"] = {{{"nodes", {parent, still}}}};
    const int times = b.AddFloats<1>({{{0}}, {{2}}});
    const int moves = b.AddFloats<3>({{{0, 0, 0}}, {{4, 0, 0}}});
    const double s = std::sin(kPi / 4), c = std::cos(kPi / 4);
    const int turns = b.AddFloats<4>({{{0, 0, 0, 1}}, {{0, float(s), 0, float(c)}}});
    Animate(b, {{parent, "translation", times, moves}, {parent, "rotation", times, turns}});
    return b;
}

TEST(SceneAnimation, ChildrenOfAnAnimatedNodeMoveWithIt) {
    absl::StatusOr<Scene> scene = Load(MovingParent());
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    const SceneAnimation& animation = *scene->animation;
    EXPECT_TRUE(animation.Moves());
    EXPECT_EQ(animation.Start(), 0);
    EXPECT_EQ(animation.End(), 2);
    // The moving triangle is posed; the still one is not even recorded.
    ASSERT_EQ(animation.meshes.size(), 1u);
    EXPECT_TRUE(animation.meshes[0].moves);
    const std::vector<Vec3d> still = scene->meshes[1].positions;

    for (const double t : {0.5, 1.0, 1.5, 3.0}) {
        ASSERT_TRUE(animation.PoseAt(t, *scene).ok());
        // Translation (2t, 0, 0) and a turn of t pi/4 about +y, both held after t = 2.
        const double u = std::min(t, 2.0);
        const Vec3d move(2 * u, 0, 0);
        const double angle = u * kPi / 4;
        const TriangleMesh& tri = scene->meshes[0];
        ExpectNear(tri.positions[0], move + RotateY(Vec3d(1, 0, 0), angle));
        ExpectNear(tri.positions[1], move + RotateY(Vec3d(2, 0, 0), angle));
        ExpectNear(tri.positions[2], move + RotateY(Vec3d(1, 1, 0), angle));
        EXPECT_EQ(scene->meshes[1].positions, still);
        ExpectNear(scene->camera.position, move + RotateY(Vec3d(0, 0, 5), angle));
        ExpectNear(scene->camera.look_at - scene->camera.position, RotateY(Vec3d(0, 0, -1), angle));
        ExpectNear(scene->point_lights[0].position, move + Vec3d(0, 2, 0));
        ExpectNear(scene->spot_lights[0].position, move + Vec3d(0, 2, 0));
        ExpectNear(scene->spot_lights[0].direction, RotateY(Vec3d(0, 0, -1), angle));
    }
}

TEST(SceneAnimation, StepAndCubicSplineChannelsReachTheNodes) {
    // The triangle's node: its translation steps from (1, 0, 0) to (1, 5, 0) at 1 s; its scale
    // goes from 1 to 3 over [0, 1] on a cubic spline with zero tangents, which at s = 1/2 is
    // the Hermite (2s^3 - 3s^2 + 1) 1 + (-2s^3 + 3s^2) 3 = 2; the parent's channels are gone.
    GltfBuilder b = MovingParent();
    b.json().erase("animations");
    const int times = b.AddFloats<1>({{{0}}, {{1}}});
    const int steps = b.AddFloats<3>({{{1, 0, 0}}, {{1, 5, 0}}});
    const int scales = b.AddFloats<3>(
        {{{0, 0, 0}}, {{1, 1, 1}}, {{0, 0, 0}}, {{0, 0, 0}}, {{3, 3, 3}}, {{0, 0, 0}}});
    Animate(b,
            {{0, "translation", times, steps, "STEP"}, {0, "scale", times, scales, "CUBICSPLINE"}});
    absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_TRUE(scene->animation->PoseAt(0.5, *scene).ok());
    ExpectNear(scene->meshes[0].positions[2], Vec3d(1, 2, 0));
    ExpectNear(scene->meshes[0].positions[1], Vec3d(3, 0, 0));
    ASSERT_TRUE(scene->animation->PoseAt(1, *scene).ok());
    ExpectNear(scene->meshes[0].positions[2], Vec3d(1, 8, 0));
    // Nothing moves the camera now.
    EXPECT_EQ(scene->animation->MovingNodes()[size_t(scene->animation->camera_node)], false);
}

TEST(SceneAnimation, FilesWithoutAnimationsSkinsOrMorphsHaveNone) {
    GltfBuilder b = MovingParent();
    b.json().erase("animations");
    absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->animation, nullptr);
}

TEST(SceneAnimation, AGltfInAJsonSceneMovesUnderItsTransform) {
    // A JSON triangle comes first, so the glTF's meshes are not the scene's first, and a
    // primitive before the animated one has only a degenerate triangle (dropped with its mesh):
    // the animation still poses the right mesh.
    GltfBuilder b = MovingParent();
    const int degenerate = b.AddIndices({0, 0, 1});
    b.json()["meshes"][0]["primitives"].insert(
        b.json()["meshes"][0]["primitives"].begin(),
        {{"attributes", {{"POSITION", 0}}}, {"indices", degenerate}});
    const std::string gltf = b.GltfEmbedded();
    const Json json = {
        {"materials", {{"grey", {{"type", "lambert"}, {"reflectance", {0.5, 0.5, 0.5}}}}}},
        {"shapes",
         {{{"type", "triangle"},
           {"material", "grey"},
           {"vertices", {{0, 0, -9}, {1, 0, -9}, {0, 1, -9}}}},
          {{"type", "gltf"},
           {"file", "moving.gltf"},
           {"transform", {{"translate", {10, 0, 0}}}}}}}};
    absl::StatusOr<Scene> scene = ParseScene(
        json.dump(), "shot.json", [&](const std::string& name) -> absl::StatusOr<std::string> {
            if (name == "moving.gltf") return gltf;
            return absl::NotFoundError(name);
        });
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    ASSERT_EQ(scene->animation->meshes.size(), 1u);
    EXPECT_EQ(scene->animation->meshes[0].mesh, 1);
    ASSERT_TRUE(scene->animation->PoseAt(2, *scene).ok());
    // At 2 s: translated (4, 0, 0) and turned a quarter about +y, then the JSON's (10, 0, 0).
    ExpectNear(scene->meshes[1].positions[1], Vec3d(14, 0, 0) + RotateY(Vec3d(2, 0, 0), kPi / 2));
    ExpectNear(scene->camera.position, Vec3d(14, 0, 0) + RotateY(Vec3d(0, 0, 5), kPi / 2));
    ExpectNear(scene->meshes[0].positions[0], Vec3d(0, 0, -9));
}

// Two joints: a root at the origin and a child at (0, 1, 0) that turns a quarter about +z
// over 1 s. A quad from (0, 0) to (1, 2): its bottom follows the root, (0, 2) the child, (1, 2)
// half each. The mesh's node is moved to (5, 5, 5), which skinning ignores.
GltfBuilder SkinnedQuad(uint16_t last_joint = 1) {
    GltfBuilder b;
    Json& j = b.json();
    const int positions = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}, {{0, 2, 0}}, {{1, 2, 0}}});
    const std::vector<uint16_t> joints = {0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, last_joint, 0, 0};
    const int joints_accessor =
        b.AddAccessor(joints.data(), joints.size() * 2, GltfBuilder::kUnsignedShort, "VEC4", 4);
    const int weights =
        b.AddFloats<4>({{{1, 0, 0, 0}}, {{1, 0, 0, 0}}, {{1, 0, 0, 0}}, {{0.5, 0.5, 0, 0}}});
    const int indices = b.AddIndices({0, 1, 3, 0, 3, 2});
    const int mesh = b.AddMesh(
        "skinned", {{"POSITION", positions}, {"JOINTS_0", joints_accessor}, {"WEIGHTS_0", weights}},
        indices, -1);
    const std::vector<float> matrices = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0,  0, 1,
                                         1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1};
    const int ibm =
        b.AddAccessor(matrices.data(), matrices.size() * 4, GltfBuilder::kFloat, "MAT4", 2);
    const int bone = b.AddNode({{"name", "Bone"}, {"translation", {0, 1, 0}}});
    const int root = b.AddNode({{"name", "Root"}, {"children", {bone}}});
    const int body =
        b.AddNode({{"name", "Body"}, {"mesh", mesh}, {"skin", 0}, {"translation", {5, 5, 5}}});
    j["skins"] = {{{"joints", {root, bone}}, {"inverseBindMatrices", ibm}}};
    j["scenes"] = {{{"nodes", {root, body}}}};
    const int times = b.AddFloats<1>({{{0}}, {{1}}});
    const double s = std::sin(kPi / 4), c = std::cos(kPi / 4);
    const int turns = b.AddFloats<4>({{{0, 0, 0, 1}}, {{0, 0, float(s), float(c)}}});
    Animate(b, {{bone, "rotation", times, turns}});
    return b;
}

TEST(SceneAnimation, ASkinnedMeshPosedEqualsTheMeshTransformedByHand) {
    absl::StatusOr<Scene> scene = Load(SkinnedQuad(), "auto");
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    ASSERT_EQ(scene->animation->meshes.size(), 1u);
    EXPECT_TRUE(scene->animation->meshes[0].moves);
    for (const double t : {0.0, 0.5, 1.0}) {
        ASSERT_TRUE(scene->animation->PoseAt(t, *scene).ok());
        // The bone's joint matrix: translate (0, 1, 0) * R_z(angle) * its inverse bind,
        // translate (0, -1, 0); the root's is the identity.
        const double angle = t * kPi / 2;
        const auto bone = [&](const Vec3d& p) {
            return Vec3d(0, 1, 0) + RotateZ(p - Vec3d(0, 1, 0), angle);
        };
        const std::vector<Vec3d>& p = scene->meshes[0].positions;
        ExpectNear(p[0], Vec3d(0, 0, 0));
        ExpectNear(p[1], Vec3d(1, 0, 0));
        ExpectNear(p[2], bone(Vec3d(0, 2, 0)));
        ExpectNear(p[3], 0.5 * Vec3d(1, 2, 0) + 0.5 * bone(Vec3d(1, 2, 0)));
    }
}

// A triangle in z = 0 with one morph target lifting it by 2 in z (and tilting its normals),
// the mesh's default weight 0.25; `animated`: a weights channel from 0 to 1 over 2 s.
GltfBuilder MorphedTriangle(bool animated) {
    GltfBuilder b;
    Json& j = b.json();
    const int positions = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}, {{0, 1, 0}}});
    const int normals = b.AddFloats<3>({{{0, 0, 1}}, {{0, 0, 1}}, {{0, 0, 1}}});
    const int lift = b.AddFloats<3>({{{0, 0, 2}}, {{0, 0, 2}}, {{0, 0, 2}}});
    const int tilt = b.AddFloats<3>({{{2, 0, 0}}, {{2, 0, 0}}, {{2, 0, 0}}});
    const int mesh = b.AddMesh("morph", {{"POSITION", positions}, {"NORMAL", normals}}, -1, -1);
    j["meshes"][mesh]["primitives"][0]["targets"] = {{{"POSITION", lift}, {"NORMAL", tilt}}};
    j["meshes"][mesh]["weights"] = {0.25};
    const int node = b.AddNode({{"name", "Morph"}, {"mesh", mesh}});
    j["scenes"] = {{{"nodes", {node}}}};
    if (animated) {
        const int times = b.AddFloats<1>({{{0}}, {{2}}});
        const int weights = b.AddFloats<1>({{{0}}, {{1}}});
        Animate(b, {{node, "weights", times, weights}});
    }
    return b;
}

TEST(SceneAnimation, AMorphTargetAtWeightHalfIsHalfway) {
    absl::StatusOr<Scene> scene = Load(MorphedTriangle(true), "auto");
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    EXPECT_TRUE(scene->animation->Moves());
    ASSERT_TRUE(scene->animation->PoseAt(1, *scene).ok());
    ExpectNear(scene->meshes[0].positions[1], Vec3d(1, 0, 1));
    ExpectNear(Vec3d(scene->meshes[0].normals[2]), Normalize(Vec3d(1, 0, 1)));
    // Before the first key the channel holds its first weight, 0, not the mesh's default.
    ASSERT_TRUE(scene->animation->PoseAt(-1, *scene).ok());
    ExpectNear(scene->meshes[0].positions[1], Vec3d(1, 0, 0));

    // Without a channel the mesh's default weight applies, and nothing moves.
    absl::StatusOr<Scene> still = Load(MorphedTriangle(false), "auto");
    ASSERT_TRUE(still.ok()) << still.status();
    ASSERT_NE(still->animation, nullptr);
    EXPECT_FALSE(still->animation->Moves());
    ASSERT_TRUE(still->animation->PoseAt(0, *still).ok());
    ExpectNear(still->meshes[0].positions[2], Vec3d(0, 1, 0.5));
}

TEST(SceneAnimation, KhronosSimpleMorphFollowsItsWeights) {
    // Two targets move vertex 2 (rest (0.5, 0.5, 0)) by (-1, 1, 0) and (1, 1, 0); the weights
    // run (0, 0), (0, 1), (1, 1), (1, 0), (0, 0) at t = 0 to 4.
    SceneOptions options;
    options.camera = "auto";
    absl::StatusOr<Scene> scene =
        LoadScene(std::string(LF_TEST_SCENES) + "/khronos/SimpleMorph/SimpleMorph.gltf", options);
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    EXPECT_EQ(scene->animation->End(), 4);
    const auto vertex2 = [&](double t) {
        EXPECT_TRUE(scene->animation->PoseAt(t, *scene).ok());
        return scene->meshes[0].positions[2];
    };
    const auto expected = [](double w0, double w1) {
        return Vec3d(0.5, 0.5, 0) + w0 * Vec3d(-1, 1, 0) + w1 * Vec3d(1, 1, 0);
    };
    ExpectNear(vertex2(1.5), expected(0.5, 1));
    ExpectNear(vertex2(3.25), expected(0.75, 0));
    ExpectNear(vertex2(-1), expected(0, 0));
    ExpectNear(scene->meshes[0].positions[1], Vec3d(1, 0, 0));
}

TEST(SceneAnimation, DracoPrimitivesAreSkinnedMorphedAndAnimatedEachWithItsOwnPoints) {
    // tests/scenes/draco/animated_draco.glb (make_draco_animated.py): one mesh of two Draco
    // primitives (185 and 61 points) under a skinned, a rigidly moving and a morphed node; over
    // 1 s the bone rises by 2, the rigid node moves 3 along +x, the morph lifts by 1 in z.
    SceneOptions options;
    options.camera = "auto";
    absl::StatusOr<Scene> scene =
        LoadScene(std::string(LF_TEST_SCENES) + "/draco/animated_draco.glb", options);
    ASSERT_TRUE(scene.ok()) << scene.status();
    ASSERT_NE(scene->animation, nullptr);
    ASSERT_EQ(scene->meshes.size(), 6u);
    EXPECT_EQ(scene->meshes[0].positions.size(), 185u);
    EXPECT_EQ(scene->meshes[1].positions.size(), 61u);
    const std::vector<TriangleMesh> rest = scene->meshes;
    ASSERT_TRUE(scene->animation->PoseAt(0.5, *scene).ok());
    const Vec3d motion[] = {{0, 1, 0},   {0, 1, 0},   {1.5, 0, 0},
                            {1.5, 0, 0}, {0, 0, 0.5}, {0, 0, 0.5}};
    for (size_t m = 0; m < 6; ++m) {
        SCOPED_TRACE(scene->meshes[m].name);
        ASSERT_EQ(scene->meshes[m].positions.size(), rest[m].positions.size());
        for (size_t v = 0; v < rest[m].positions.size(); ++v) {
            ExpectNear(scene->meshes[m].positions[v], rest[m].positions[v] + motion[m], 1e-5);
        }
    }
}

TEST(SceneAnimation, APoseBeyondTheCoordinateRangeIsRefusedNamingNodeAndTime) {
    GltfBuilder b = MovingParent();
    const int times = b.AddFloats<1>({{{0}}, {{1}}});
    const int far = b.AddFloats<3>({{{0, 0, 0}}, {{0, 4e15f, 0}}});
    // Node 0 holds the triangle: its translation (1, 0, 0) becomes (0, 4e15, 0), under the
    // parent at (2, 0, 0) at 1 s.
    Animate(b, {{0, "translation", times, far}});
    absl::StatusOr<Scene> scene = Load(b);
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_TRUE(scene->animation->PoseAt(0.1, *scene).ok());
    const absl::Status status = scene->animation->PoseAt(1, *scene);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(status.message()),
                HasSubstr("anim.gltf: nodes[0] \"Tri\" at 1 s: mesh \"tri[0]\" "
                          "vertex 0 at (2, 4e+15, 0) is beyond ±1e+15"));
}

std::string LoadError(const GltfBuilder& b) {
    absl::StatusOr<Scene> scene = Load(b, "auto");
    EXPECT_FALSE(scene.ok());
    return std::string(scene.status().message());
}

// Malformed animation data does not refuse the file: the still loads in the rest pose `good`
// loads in, with one warning naming `what`, no animation, and the error for whoever needs
// the scene in time.
void ExpectIgnoredInAStill(const GltfBuilder& bad, const GltfBuilder& good,
                           const std::string& what) {
    SCOPED_TRACE(what);
    testing::CapturedSceneLog().str("");
    absl::StatusOr<Scene> scene = Load(bad, "auto");
    ASSERT_TRUE(scene.ok()) << scene.status();
    const std::string log = testing::CapturedSceneLog().str();
    EXPECT_THAT(log, HasSubstr("anim.gltf: animation ignored: " + what)) << log;
    EXPECT_EQ(log.find("animation ignored"), log.rfind("animation ignored")) << log;
    EXPECT_EQ(scene->animation, nullptr);
    EXPECT_EQ(scene->animation_error.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(scene->animation_error.message(), "anim.gltf: " + what);
    absl::StatusOr<Scene> rest = Load(good, "auto");
    ASSERT_TRUE(rest.ok()) << rest.status();
    ASSERT_EQ(scene->meshes.size(), rest->meshes.size());
    for (size_t m = 0; m < rest->meshes.size(); ++m) {
        EXPECT_EQ(scene->meshes[m].positions, rest->meshes[m].positions);
    }
}

TEST(SceneAnimation, BadAnimationsAreIgnoredInAStillNamingWhere) {
    {
        GltfBuilder b = MovingParent();
        b.json()["animations"][0]["channels"][1]["target"]["node"] = 42;
        ExpectIgnoredInAStill(b, MovingParent(),
                              "animations[0] \"Action\".channels[1]: target node 42 does not "
                              "exist (the file has 6 nodes)");
    }
    {
        GltfBuilder b = MovingParent();
        b.json()["nodes"][0]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 1};
        b.json()["nodes"][0].erase("translation");
        GltfBuilder good = b;
        const int times = good.AddFloats<1>({{{0}}, {{1}}});
        const int values = good.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}});
        b = good;
        Animate(b, {{0, "translation", times, values}});
        ExpectIgnoredInAStill(b, good,
                              "animations[1] \"Action\".channels[0]: target nodes[0] \"Tri\" has "
                              "a matrix; channels may only target nodes given by translation, "
                              "rotation and scale");
    }
    {
        GltfBuilder b = MovingParent();
        const int times = b.AddFloats<1>({{{0}}, {{1}}, {{1}}});
        const int values = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}, {{2, 0, 0}}});
        GltfBuilder good = b;
        Animate(b, {{0, "translation", times, values}});
        ExpectIgnoredInAStill(b, good,
                              "animations[1] \"Action\".samplers[0]: input times are not "
                              "strictly increasing: time 2 is 1 after 1");
    }
    {
        GltfBuilder b = MovingParent();
        const int times = b.AddFloats<1>({{{0}}, {{1}}});
        const int values = b.AddFloats<3>({{{0, 0, 0}}, {{1, NAN, 0}}});
        GltfBuilder good = b;
        Animate(b, {{0, "translation", times, values}});
        ExpectIgnoredInAStill(b, good,
                              "animations[1] \"Action\".samplers[0]: output keyframe 1 (at 1 s) "
                              "number 1 is nan");
    }
    {
        GltfBuilder b = MovingParent();
        const int times = b.AddFloats<1>({{{0}}, {{INFINITY}}});
        const int values = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}});
        GltfBuilder good = b;
        Animate(b, {{0, "translation", times, values}});
        ExpectIgnoredInAStill(b, good, "animations[1] \"Action\".samplers[0]: input time 1 is inf");
    }
    {
        GltfBuilder b = MovingParent();
        const int times = b.AddFloats<1>({{{0}}, {{1}}});
        const int values = b.AddFloats<1>({{{0}}, {{1}}});
        GltfBuilder good = b;
        Animate(b, {{0, "weights", times, values}});
        ExpectIgnoredInAStill(b, good,
                              "animations[1] \"Action\".channels[0]: animates the morph weights "
                              "of nodes[0] \"Tri\", whose mesh has no morph targets");
    }
    ExpectIgnoredInAStill(SkinnedQuad(7), SkinnedQuad(),
                          "meshes[0] \"skinned\".primitives[0].attributes.JOINTS_0: vertex 3 "
                          "names joint 7, but skins[0] has 2 joints");
    {
        GltfBuilder b = SkinnedQuad();
        b.json()["skins"][0]["joints"][1] = 12;
        ExpectIgnoredInAStill(b, SkinnedQuad(),
                              "skins[0].joints[1]: node 12 does not exist (the file has 3 nodes)");
    }
    {
        GltfBuilder b = MorphedTriangle(true);
        b.json()["meshes"][0]["weights"] = {0.25, 0.5};
        ExpectIgnoredInAStill(b, MorphedTriangle(true),
                              "meshes[0] \"morph\": weights has 2 numbers for 1 morph targets");
    }
}

TEST(SceneAnimation, ABadIncludedGltfDropsTheWholeAnimationNamingTheFile) {
    // A JSON scene with a keyframed sphere includes a glTF whose channel targets node 42: the
    // still loads, and the scene has no animation at all (frames are refused with the error).
    GltfBuilder b = MovingParent();
    b.json()["animations"][0]["channels"][1]["target"]["node"] = 42;
    const std::string gltf = b.GltfEmbedded();
    const Json json = {
        {"materials",
         {{"glow", {{"type", "lambert"}, {"emission", {1, 1, 1}}, {"reflectance", {0, 0, 0}}}}}},
        {"shapes",
         {{{"type", "sphere"},
           {"material", "glow"},
           {"center", {0, 0, 0}},
           {"radius", 1},
           {"transform",
            {{"keyframes",
              {{{"time", 0}, {"translate", {0, 0, 0}}},
               {{"time", 1}, {"translate", {1, 0, 0}}}}}}}},
          {{"type", "gltf"}, {"file", "models/bad.gltf"}}}}};
    testing::CapturedSceneLog().str("");
    absl::StatusOr<Scene> scene = ParseScene(
        json.dump(), "shot.json", [&](const std::string& name) -> absl::StatusOr<std::string> {
            if (name == "models/bad.gltf") return gltf;
            return absl::NotFoundError(name);
        });
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->animation, nullptr);
    const std::string what =
        "animations[0] \"Action\".channels[1]: target node 42 does not exist (the file has 6 "
        "nodes)";
    EXPECT_EQ(scene->animation_error.message(), "models/bad.gltf: " + what);
    EXPECT_THAT(testing::CapturedSceneLog().str(),
                HasSubstr("shot.json: models/bad.gltf: animation ignored: " + what));
}

TEST(SceneAnimation, AHierarchyThatIsNotATreeIsStillRefused) {
    // A scene root ("Still") on a cycle of children: the animation's tree has no place for it,
    // and the traversal refuses the file.
    GltfBuilder b = MovingParent();
    const int loop = b.AddNode({{"name", "Loop"}, {"children", {5}}});
    b.json()["nodes"][5]["children"] = {loop};
    EXPECT_THAT(LoadError(b), HasSubstr("reached twice: the node hierarchy is not a tree"));
}

}  // namespace
}  // namespace lf
