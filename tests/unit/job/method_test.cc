// The rendering methods a job may name (lf/job/method_registry.h): each of them passes, anything
// else is refused as unknown with the list; and a Whitted render's header names its method and
// light sampling.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "lf/job/job_spec.h"
#include "lf/job/merge.h"
#include "lf/job/method_registry.h"
#include "lf/job/render_metadata.h"

namespace lf {
namespace {

TEST(Method, EveryMethodPassesTheJobCheck) {
    for (const char* method : {"path", "radiosity", "whitted", "light", "bdpt", "ppm"}) {
        JobSpec spec;
        spec.method = method;
        EXPECT_TRUE(ParseMethod(method).ok()) << method;
        EXPECT_TRUE(CheckJobSettings(spec).ok()) << method << ": " << CheckJobSettings(spec);
    }
}

TEST(Method, UnknownMethodIsInvalidAndListsEveryMethod) {
    const absl::Status s = ParseMethod("photon").status();
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    const std::string message(s.message());
    for (const char* name : {"path", "radiosity", "whitted", "bdpt", "light", "ppm"}) {
        EXPECT_NE(message.find(name), std::string::npos) << name << " in " << message;
    }
    EXPECT_EQ(ParseMethod("").status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(ParseMethod("Whitted").status().code(), absl::StatusCode::kInvalidArgument);
}

// Whitted samples lights as the path tracer does, so its header names the light strategy, and
// nothing of radiosity.
TEST(Method, WhittedHeaderNamesItsMethodAndLightSampling) {
    RenderMetadata m;
    m.scene_hash = "abc";
    m.method = "whitted";
    m.spp = 1;
    m.light_strategy = LightStrategy::kPower;
    absl::StatusOr<RenderDescription> d = DescribeRender(m, EmptyRenderImage(4, 4), true);
    ASSERT_TRUE(d.ok()) << d.status();
    EXPECT_EQ(std::get<std::string>(d->attributes.at("lightfarm.method")), "whitted");
    EXPECT_EQ(std::get<std::string>(d->attributes.at("lightfarm.lightSampling")), "power");
    for (const auto& [name, value] : d->attributes) {
        EXPECT_NE(name.rfind("lightfarm.radiosity.", 0), 0u) << name;
    }
}

// Light tracing and bdpt reach the camera through its importance, which an orthographic camera
// (one direction) does not have: they refuse it by name; the others render it.
TEST(Method, OnlyMethodsThatTraceFromTheCameraTakeAnOrthographicCamera) {
    Scene scene;
    scene.camera.projection = CameraSpec::Projection::kOrthographic;
    for (const MethodInfo& info : AllMethods()) {
        if (info.method == Method::kRadiosity) continue;  // refuses this empty scene
        const absl::Status s = CheckMethodTakesScene(info.method, scene);
        if (info.splats_light_paths) {
            EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << info.name;
            EXPECT_NE(s.message().find("orthographic cameras are not supported"), std::string::npos)
                << s;
        } else {
            EXPECT_TRUE(s.ok()) << info.name << ": " << s;
        }
    }
}

// Only the path tracer and bdpt render scattering and grid media and a camera in a medium, and
// only the path tracer emitting media; the others refuse them naming themselves and the medium.
// A homogeneous absorber (Beer's law) every method takes.
TEST(Method, OnlyThePathTracerAndBdptTakeMediaBeyondAbsorbers) {
    Medium absorber;
    absorber.name = "ink";
    absorber.sigma_a = Rgb(1, 2, 3);
    Medium fog = absorber, glow = absorber, smoke = absorber;
    fog.name = "fog";
    fog.sigma_s = Rgb(0.5f);
    glow.name = "glow";
    glow.emission = Rgb(1);
    smoke.name = "smoke";
    smoke.type = Medium::Type::kGrid;
    const auto with = [](std::vector<Medium> media, int camera_medium = -1) {
        Scene scene;
        scene.media = std::move(media);
        scene.camera_medium = camera_medium;
        return scene;
    };
    const std::pair<Scene, std::string> refused[] = {
        {with({absorber, fog}), "medium \"fog\" scatters light (sigma_s > 0)"},
        {with({glow}), "medium \"glow\" emits light"},
        {with({smoke}), "medium \"smoke\" is a grid (heterogeneous)"},
        {with({absorber}, 0), "the camera is in medium \"ink\""},
    };
    for (const auto& [scene, why] : refused) {
        EXPECT_EQ(MediaLimitation(scene), why);
        EXPECT_TRUE(CheckMethodTakesScene(Method::kPath, scene).ok());
        const bool emits = why.find("emits light") != std::string::npos;
        EXPECT_EQ(BdptMediaLimitation(scene), emits ? why : "");
        for (const MethodInfo& info : AllMethods()) {
            if (info.method == Method::kPath) continue;
            const absl::Status s = CheckMethodTakesScene(info.method, scene);
            if (info.method == Method::kBdpt && !emits) {
                EXPECT_TRUE(s.ok()) << s;
                continue;
            }
            EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << info.name << ": " << s;
            const std::string name = info.name;
            const std::string expected =
                "method " + name + ": " + why +
                (info.method == Method::kWhitted || info.method == Method::kRadiosity
                     ? ", which " + name + " does not model"
                     : ": not yet supported by " + name) +
                "; use --method path";
            EXPECT_EQ(s.message(), expected);
        }
    }
    const Scene absorbing = with({absorber});
    EXPECT_EQ(MediaLimitation(absorbing), "");
    for (const Method m :
         {Method::kPath, Method::kWhitted, Method::kLight, Method::kBdpt, Method::kPpm}) {
        EXPECT_TRUE(CheckMethodTakesScene(m, absorbing).ok()) << MethodName(m);
    }
}

// Radiosity takes triangles only: its scene preparation meshes the spheres, and the scene hash
// (the input's name) stays; every other method keeps the analytic spheres.
TEST(Method, OnlyRadiosityMeshesSpheres) {
    for (const MethodInfo& info : AllMethods()) {
        Scene scene;
        scene.materials.emplace_back();
        scene.spheres.push_back({"ball", 0, Vec3d(), 1});
        scene.content_hash = "input";
        PrepareSceneFor(info.method, scene);
        EXPECT_EQ(scene.content_hash, "input");
        if (info.method == Method::kRadiosity) {
            EXPECT_TRUE(scene.spheres.empty());
            ASSERT_EQ(scene.meshes.size(), 1u);
            EXPECT_EQ(scene.meshes[0].name, "ball");
        } else {
            EXPECT_EQ(scene.spheres.size(), 1u) << info.name;
            EXPECT_TRUE(scene.meshes.empty()) << info.name;
        }
    }
}

}  // namespace
}  // namespace lf
