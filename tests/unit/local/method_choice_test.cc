// `--method auto` (lf/local/method_choice.h) on the scenes the CLI tests use: caustics from a
// small lamp take bdpt, an all-Lambertian room radiosity, a lit plane Whitted, no light the
// path tracer; a requested method is taken as it is.
#include "lf/local/method_choice.h"

#include <gtest/gtest.h>

#include <string>

#include "lf/core/scene_loader.h"

namespace lf {
namespace {

Scene Load(const std::string& name) {
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/" + name);
    EXPECT_TRUE(scene.ok()) << scene.status();
    return *scene;
}

Scene Parse(const std::string& json) {
    absl::StatusOr<Scene> scene =
        ParseScene(json, "scene.json", [](const std::string& path) -> absl::StatusOr<std::string> {
            return absl::NotFoundError(path);
        });
    EXPECT_TRUE(scene.ok()) << scene.status();
    return *scene;
}

constexpr const char* kPlane = R"({"camera": {"position": [0, 3, 0], "look_at": [0, 0, 0],
        "up": [0, 0, 1], "fov_y_deg": 60, "resolution": [16, 16]},
    "materials": {"grey": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5]}},
    "shapes": [{"type": "quad", "material": "grey",
                "vertices": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]}])";

TEST(MethodChoice, AutoPicksTheMethodTheSceneRequires) {
    const MethodChoice caustic = ChooseMethod(Load("caustic.json"), std::nullopt);
    EXPECT_EQ(caustic.method, Method::kBdpt);
    EXPECT_EQ(caustic.why.rfind("caustics (L S+ D E): light from emitter \"light\" (0.", 0), 0u)
        << caustic.why;

    const MethodChoice cornell = ChooseMethod(Load("cornell_box.json"), std::nullopt);
    EXPECT_EQ(cornell.method, Method::kRadiosity);
    EXPECT_EQ(cornell.why, "every material is Lambertian");

    const MethodChoice plane = ChooseMethod(
        Parse(std::string(kPlane) +
              R"(, "lights": [{"type": "point", "position": [0, 2, 0], "power": [5, 5, 5]}]})"),
        std::nullopt);
    EXPECT_EQ(plane.method, Method::kWhitted);
    EXPECT_EQ(plane.why,
              "no interreflection and no caustics: classic ray tracing is exact here (point-like "
              "lights only)");

    const MethodChoice dark = ChooseMethod(Parse(std::string(kPlane) + "}"), std::nullopt);
    EXPECT_EQ(dark.method, Method::kPath);
    EXPECT_EQ(dark.why, "the scene has no lights: the image is black whatever the method");
}

// Scattering media are the path tracer's and bdpt's alone: auto takes the path tracer where it
// would otherwise pick Whitted; a homogeneous absorber (Beer's law) leaves the choice as it was.
TEST(MethodChoice, AutoTakesThePathTracerForMediaOnlyItRenders) {
    const std::string lit =
        R"(, "lights": [{"type": "point", "position": [0, 2, 0], "power": [5, 5, 5]}]})";
    const MethodChoice fog = ChooseMethod(
        Parse(std::string(kPlane) +
              R"(, "media": {"fog": {"type": "homogeneous", "sigma_s": [1, 1, 1]}})" + lit),
        std::nullopt);
    EXPECT_EQ(fog.method, Method::kPath);
    EXPECT_EQ(fog.why,
              "medium \"fog\" scatters light (sigma_s > 0): only the path tracer and bdpt render "
              "it");

    const MethodChoice absorber = ChooseMethod(
        Parse(std::string(kPlane) +
              R"(, "media": {"ink": {"type": "homogeneous", "sigma_a": [1, 1, 1]}})" + lit),
        std::nullopt);
    EXPECT_EQ(absorber.method, Method::kWhitted);

    // An interface between media passes light straight on: it neither scatters nor focuses.
    std::string boundary = kPlane;
    boundary.replace(boundary.find(R"("type": "lambert")"), 17, R"("type": "interface")");
    boundary.erase(boundary.find(R"(, "reflectance": [0.5, 0.5, 0.5])"), 32);
    const SceneTransport t = AnalyzeTransport(Parse(boundary + "}"));
    EXPECT_FALSE(t.diffuse);
    EXPECT_TRUE(t.specular.empty());
}

TEST(MethodChoice, RequestedMethodIsTaken) {
    const MethodChoice c = ChooseMethod(Load("cornell_box.json"), Method::kPpm);
    EXPECT_EQ(c.method, Method::kPpm);
    EXPECT_EQ(c.why, "requested");
}

// A modelling tool's room (principled materials, a textured floor, point and spot lights) is
// radiosity's to render, but it would drop the plaster's specular layer: auto takes the path
// tracer and says what radiosity would drop; asked for, radiosity takes the scene.
TEST(MethodChoice, RadiosityTakesAModellingToolsRoomAndSaysWhatItDrops) {
    const Scene room = Load("radiosity/room.gltf");
    const MethodChoice automatic = ChooseMethod(room, std::nullopt);
    EXPECT_EQ(automatic.method, Method::kPath);
    EXPECT_EQ(automatic.why,
              "radiosity would keep only the diffuse parts (dropping specular reflection: "
              "\"white plaster\")");
    EXPECT_TRUE(CheckMethodTakesScene(Method::kRadiosity, room).ok());
}

}  // namespace
}  // namespace lf
