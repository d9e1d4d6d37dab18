#include "lf/core/scene_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/auto_camera.h"
#include "lf/core/file_util.h"
#include "lf/core/gltf_scene.h"
#include "lf/core/log.h"
#include "lf/core/mesh_tangents.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/scene_animation.h"
#include "scene_json.h"
#include "scene_parser.h"

namespace lf {
namespace scene_internal {

Scene SceneParser::Parse(const Json& json, const std::string& text) {
    hash_.Update(text);
    const Node root(json, "", &warnings_);
    root.ExpectObject({"version", "camera", "materials", "shapes", "lights", "media"});
    if (const std::optional<Node> version = root.Find("version")) {
        if (version->Number() != 1) version->Fail("unsupported; this build reads version 1");
    }
    Scene scene;
    textures_ = &scene.textures;
    // Before the camera and the shapes, which name media.
    if (const std::optional<Node> media = root.Find("media")) ParseMedia(*media, scene);
    // Optional when an included glTF may bring a camera, or --camera auto frames the scene
    // (ResolveCamera).
    const std::optional<Node> camera = IncludesGltf(root) || options_.camera == kAutoCameraName
                                           ? root.Find("camera")
                                           : std::optional(root.Get("camera"));
    if (camera) {
        scene.camera = ParseCamera(*camera);
        if (const std::optional<Node> medium = camera->Find("medium")) {
            scene.camera_medium = MediumIndex(*medium);
        }
    }

    const Node materials = root.Get("materials");
    materials.RequireObject();
    for (const auto& [name, value] : materials.json().items()) {
        material_index_[name] = int(scene.materials.size());
        scene.materials.push_back(
            ParseMaterial(name, Node(value, absl::StrCat("materials.", name), &warnings_)));
    }

    const std::vector<Node> shapes = root.Get("shapes").Elements();
    if (shapes.empty()) root.Get("shapes").Fail("no shapes; a scene needs at least one");
    for (const Node& shape : shapes) ParseShape(shape, scene);
    ResolveEmittedPower(scene);

    if (const std::optional<Node> lights = root.Find("lights")) {
        for (const Node& light : lights->Elements()) ParseLight(light, scene);
    }

    ResolveCamera(root, camera.has_value(), scene);
    return Finish(scene);
}

Scene SceneParser::ParseGltf(const std::string& bytes, const std::string& source) {
    hash_.Update(bytes);
    Scene scene;
    // The reader resolves names beside the scene file already.
    ImportGltf(
        bytes, std::filesystem::path(source).filename().string(), "", Affine(), scene,
        [](const absl::Status& s) { throw LoadError{s}; }, false);
    if (FramesTheScene()) {
        scene.camera = FrameScene(scene);
        return Finish(scene);
    }
    UseGltfCamera("", scene);
    return Finish(scene);
}

Scene SceneParser::Finish(Scene& scene) {
    if (options_.width > 0 || options_.height > 0) {
        if (!(options_.width >= 1 && options_.width <= kMaxResolution && options_.height >= 1 &&
              options_.height <= kMaxResolution &&
              int64_t(options_.width) * options_.height <= kMaxPixels)) {
            throw LoadError{absl::InvalidArgumentError(absl::StrCat(
                "resolution ", options_.width, "x", options_.height, ": expected 1 to ",
                kMaxResolution, " per side and at most 2^28 pixels"))};
        }
        scene.camera.width = options_.width;
        scene.camera.height = options_.height;
    }
    if (options_.filter) {
        if (const absl::Status status = CheckPixelFilter(*options_.filter); !status.ok()) {
            throw LoadError{absl::InvalidArgumentError(absl::StrCat(
                "--filter ", PixelFilterTypeName(options_.filter->type), ": ", status.message()))};
        }
        scene.camera.filter = *options_.filter;
    }
    if (!options_.sky.empty()) ApplySky(scene);
    AddAttenuationMedia(scene);
    if (!scene.HasLights()) {
        warnings_.push_back("no emissive shape and no light: the image will be black");
    }
    scene.dropped_degenerate = dropped_degenerate_;
    scene.animation_error = animation_error_;
    if (animation_error_.ok() && !animation_.Empty()) {
        scene.animation = std::make_shared<const SceneAnimation>(animation_);
    }
    scene.content_hash = hash_.Hex();
    return std::move(scene);
}

bool SceneParser::IncludesGltf(const Node& root) {
    const Json& shapes = root.json().contains("shapes") ? root.json()["shapes"] : Json();
    return shapes.is_array() && std::any_of(shapes.begin(), shapes.end(), [](const Json& s) {
               return s.is_object() && s.value("type", Json()) == "gltf";
           });
}

bool SceneParser::FramesTheScene() const {
    return options_.camera == kAutoCameraName &&
           std::none_of(gltf_cameras_.begin(), gltf_cameras_.end(),
                        [](const GltfCamera& c) { return c.name == kAutoCameraName; });
}

void SceneParser::ResolveCamera(const Node& root, bool json_camera, Scene& scene) {
    if (FramesTheScene()) {
        scene.camera = FrameScene(scene);
        return;
    }
    if (json_camera && options_.camera.empty()) {
        animation_.camera_node = json_camera_node_;
        return;
    }
    if (!json_camera && gltf_cameras_.empty()) {
        root.Fail("missing required key \"camera\" (no included glTF has a camera)");
    }
    if (gltf_cameras_.empty()) {
        root.Fail(absl::StrCat("--camera \"", options_.camera,
                               "\": the scene has no named cameras (only glTF cameras have "
                               "names)"));
    }
    UseGltfCamera("--camera: ", scene);
}

void SceneParser::UseGltfCamera(const std::string& prefix, Scene& scene) {
    absl::StatusOr<const GltfCamera*> camera = ChooseGltfCamera(gltf_cameras_, options_.camera);
    if (!camera.ok()) {
        throw LoadError{
            absl::Status(camera.status().code(), absl::StrCat(prefix, camera.status().message()))};
    }
    scene.camera = (*camera)->spec;
    animation_.camera_node = (*camera)->node;
}

}  // namespace scene_internal

SceneFileReader ReadBeside(const std::string& base_dir) {
    return [base_dir](const std::string& name) {
        std::filesystem::path path(name);
        if (path.is_relative()) path = std::filesystem::path(base_dir) / path;
        return ReadFile(path.lexically_normal().string());
    };
}

absl::StatusOr<Scene> LoadScene(const std::string& path, const SceneOptions& options) {
    absl::StatusOr<std::string> text = ReadFile(path);
    if (!text.ok()) return text.status();
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    return ParseScene(*text, path, ReadBeside(parent.empty() ? "." : parent.string()), options);
}

absl::StatusOr<Scene> ParseScene(const std::string& json_text, const std::string& source,
                                 const SceneFileReader& read_file, const SceneOptions& options) {
    using scene_internal::Json, scene_internal::LoadError, scene_internal::ParseJson,
        scene_internal::SceneParser;
    const bool gltf = IsGltfName(source);
    Json root;
    if (!gltf) {
        if (absl::Status status = ParseJson(json_text, source, root); !status.ok()) return status;
    }
    SceneParser parser(read_file, options);
    absl::StatusOr<Scene> scene;
    try {
        scene = gltf ? parser.ParseGltf(json_text, source) : parser.Parse(root, json_text);
        scene->source = source;
        if (absl::Status s = CheckCoordinates(*scene); !s.ok()) throw LoadError{s};
        // After every transform: tangents are not transformed with the meshes.
        ComputeMissingTangents(*scene);
    } catch (const LoadError& e) {
        scene = absl::Status(e.status.code(), absl::StrCat(source, ": ", e.status.message()));
    }
    // Also on failure: an unknown key is often the misspelling behind a missing one.
    const std::shared_ptr<spdlog::logger> logger = NamedLogger("scene");
    for (const std::string& warning : parser.warnings()) logger->warn("{}: {}", source, warning);
    if (scene.ok() && scene->dropped_degenerate > 0) {
        logger->warn("{}: dropped {} degenerate triangles (zero area or repeated vertices)", source,
                     scene->dropped_degenerate);
    }
    return scene;
}

}  // namespace lf
