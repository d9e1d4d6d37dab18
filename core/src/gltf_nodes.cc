#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "gltf_importer.h"
#include "lf/core/photometry.h"

namespace lf::gltf_internal {
namespace {

// The extensions this importer reads. Anything else in extensionsUsed loses what it describes
// (a warning); in extensionsRequired it is an error.
const std::set<std::string>& SupportedExtensions() {
    static const std::set<std::string> kSupported = {
        "KHR_lights_punctual",        "KHR_materials_emissive_strength",
        "KHR_materials_ior",          "KHR_materials_transmission",
        "KHR_materials_volume",       "KHR_materials_specular",
        "KHR_materials_unlit",        "KHR_materials_clearcoat",
        "KHR_materials_sheen",        "KHR_texture_transform",
        "KHR_draco_mesh_compression",
    };
    return kSupported;
}

// What a render loses when it ignores an extension, for the warning.
std::string WhatIsLost(const std::string& extension) {
    static const std::map<std::string, std::string> kLost = {
        {"KHR_materials_iridescence", "thin-film iridescence"},
        {"KHR_materials_anisotropy", "anisotropic roughness; rendered isotropic"},
        {"KHR_materials_dispersion", "dispersion; one IOR for all wavelengths"},
        {"KHR_materials_pbrSpecularGlossiness",
         "the specular-glossiness material; the "
         "metallic-roughness fallback is used"},
        {"KHR_materials_variants", "material variants; the default materials are used"},
        {"KHR_texture_basisu", "Basis Universal textures; the fallback images are used"},
        {"EXT_texture_webp", "WebP textures; the fallback images are used"},
        {"EXT_meshopt_compression", "meshopt-compressed geometry; the fallback is used"},
        {"KHR_mesh_quantization", "nothing if the quantized attributes are floats"},
        {"EXT_mesh_gpu_instancing", "the instances; each mesh is rendered once"},
    };
    const auto found = kLost.find(extension);
    return found == kLost.end() ? "whatever it describes is ignored" : found->second;
}

}  // namespace

Vec3d NodeTranslation(const tinygltf::Node& node) {
    const std::vector<double>& t = node.translation;
    return t.empty() ? Vec3d(0, 0, 0) : Vec3d(t[0], t[1], t[2]);
}

std::array<double, 4> NodeRotation(const tinygltf::Node& node, const std::string& where) {
    if (node.rotation.empty()) return {0, 0, 0, 1};
    const std::vector<double>& q = node.rotation;
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(norm > 0)) Fail(where, "rotation is the zero quaternion");
    return {q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm};
}

Vec3d NodeScale(const tinygltf::Node& node) {
    const std::vector<double>& s = node.scale;
    return s.empty() ? Vec3d(1, 1, 1) : Vec3d(s[0], s[1], s[2]);
}

// The node's own transform: its matrix (column-major) or translation * rotation * scale.
Affine LocalTransform(const tinygltf::Node& node, const std::string& where) {
    Affine local;
    auto& m = local.m;
    auto check = [&](const std::vector<double>& v, size_t size, const char* key) {
        if (!v.empty() && v.size() != size) {
            Fail(where, absl::StrCat(key, " has ", v.size(), " numbers, expected ", size));
        }
        for (double x : v) {
            if (!std::isfinite(x)) Fail(where, absl::StrCat(key, " holds ", x));
        }
    };
    check(node.matrix, 16, "matrix");
    check(node.translation, 3, "translation");
    check(node.rotation, 4, "rotation");
    check(node.scale, 3, "scale");
    if (!node.matrix.empty()) {
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 4; ++c) m[r][c] = node.matrix[c * 4 + r];
        }
        if (node.matrix[3] != 0 || node.matrix[7] != 0 || node.matrix[11] != 0 ||
            node.matrix[15] != 1) {
            Fail(where, "matrix is not affine (its last row must be 0, 0, 0, 1)");
        }
        return local;
    }
    return Affine::FromTrs(NodeTranslation(node), NodeRotation(node, where), NodeScale(node));
}

void GltfImporter::Import() {
    CheckExtensions();
    if (model_.scenes.empty()) Fail("scenes", "the file has no scene");
    int index = model_.defaultScene;
    if (index < 0) index = 0;
    if (index >= int(model_.scenes.size())) {
        Fail("scene", absl::StrCat(index, " is not a scene index (the file has ",
                                   model_.scenes.size(), ")"));
    }
    if (model_.scenes.size() > 1) {
        Warn(absl::StrCat("renders scene ", index, " of ", model_.scenes.size(),
                          " (the file's default)"));
    }
    // Every material, in file order, so scene material i is glTF material i (after those
    // already in the scene); the default material only when a primitive needs it.
    for (int i = 0; i < int(model_.materials.size()); ++i) Material(i, "materials");
    animating_ = options_.animation && Animates();
    AnimationStep([&] {
        ReadNodeTree();
        ReadAnimations();
        moving_ = options_.animation->MovingNodes();
    });
    visited_.assign(model_.nodes.size(), false);
    const tinygltf::Scene& gltf_scene = model_.scenes[size_t(index)];
    for (size_t i = 0; i < gltf_scene.nodes.size(); ++i) {
        VisitNode(gltf_scene.nodes[i], options_.transform,
                  absl::StrCat("scenes[", index, "].nodes[", i, "]"));
    }
    if (range_ignored_) Warn("KHR_lights_punctual range ignored: lights fall off as 1/r^2");
    WarnTallies();
}

void GltfImporter::WarnTallies() {
    constexpr size_t kNamed = 3;
    for (const auto& [what, t] : tallies_) {
        const size_t n = t.wheres.size();
        const std::vector<std::string> named(t.wheres.begin(),
                                             t.wheres.begin() + ptrdiff_t(std::min(n, kNamed)));
        Warn(absl::StrCat(what, " in ", n, " ", t.noun, n == 1 ? "" : "s", ": ",
                          absl::StrJoin(named, ", "), n > kNamed ? ", ..." : ""));
    }
}

void GltfImporter::CheckExtensions() {
    std::vector<std::string> unsupported;
    for (const std::string& e : model_.extensionsRequired) {
        if (!SupportedExtensions().contains(e)) unsupported.push_back(e);
    }
    if (!unsupported.empty()) {
        Fail("extensionsRequired",
             absl::StrCat("lightfarm does not support ", absl::StrJoin(unsupported, ", "),
                          "; supported: ", absl::StrJoin(SupportedExtensions(), ", ")));
    }
    for (const std::string& e : model_.extensionsUsed) {
        if (!SupportedExtensions().contains(e)) {
            Warn(absl::StrCat("extension ", e, " not supported: ", WhatIsLost(e)));
        }
    }
}

void GltfImporter::VisitNode(int index, const Affine& parent, const std::string& ref) {
    if (index < 0 || index >= int(model_.nodes.size())) {
        Fail(ref,
             absl::StrCat(index, " is not a node index (the file has ", model_.nodes.size(), ")"));
    }
    const tinygltf::Node& node = model_.nodes[size_t(index)];
    const std::string where = absl::StrCat("nodes[", index, "]", Quoted(node.name));
    // glTF's hierarchy is a forest: a node reached twice is a cycle or a shared child.
    if (visited_[size_t(index)]) Fail(where, "reached twice: the node hierarchy is not a tree");
    visited_[size_t(index)] = true;
    const Affine world = LocalTransform(node, where).Then(parent);
    // Each node's numbers are finite, but a chain of large scales can overflow.
    if (!world.IsFinite()) Fail(where, "its world transform overflows double range");
    const Vec3d origin = world.Apply(Vec3d(0, 0, 0));
    if (!(std::abs(origin.x) <= kMaxCoordinate && std::abs(origin.y) <= kMaxCoordinate &&
          std::abs(origin.z) <= kMaxCoordinate)) {
        Fail(where, absl::StrCat("its world translation (", origin.x, ", ", origin.y, ", ",
                                 origin.z, ") is beyond ±", kMaxCoordinate));
    }
    const Counts before = CountObjects();
    if (node.mesh >= 0) AddMesh(index, world, where);
    if (node.camera >= 0) AddCamera(node, world, where);
    if (const auto light = node.extensions.find("KHR_lights_punctual");
        light != node.extensions.end()) {
        AddLight(light->second.Get("light"), world, where);
    }
    if (animating_) AnimateNode(index, before);
    for (size_t i = 0; i < node.children.size(); ++i) {
        VisitNode(node.children[i], world, absl::StrCat(where, ".children[", i, "]"));
    }
}

void GltfImporter::AddCamera(const tinygltf::Node& node, const Affine& world,
                             const std::string& where) {
    if (node.camera >= int(model_.cameras.size())) {
        Fail(where, absl::StrCat("camera ", node.camera, " does not exist"));
    }
    const tinygltf::Camera& camera = model_.cameras[size_t(node.camera)];
    const std::string at = absl::StrCat("cameras[", node.camera, "]", Quoted(camera.name));
    GltfCamera out;
    out.name = node.name.empty() ? camera.name : node.name;
    // A camera that is not rendered must not refuse the file: its faults wait for ChooseGltfCamera.
    const auto refuse = [&](const std::string& object, const std::string& message) {
        out.error = absl::StrCat(object, ": ", message);
        cameras_.push_back(std::move(out));
    };
    CameraSpec& spec = out.spec;
    if (!PlaceGltfCamera(world, spec)) return refuse(where, "its transform is singular");
    double aspect = 1;
    if (camera.type == "perspective") {
        const tinygltf::PerspectiveCamera& p = camera.perspective;
        if (!(p.yfov > 0 && p.yfov < std::numbers::pi)) {
            return refuse(at, absl::StrCat("yfov ", p.yfov, " must be in (0, pi) radians"));
        }
        spec.fov_y_deg = p.yfov * 180 / std::numbers::pi;
        if (p.aspectRatio > 0) aspect = p.aspectRatio;
    } else if (camera.type == "orthographic") {
        const tinygltf::OrthographicCamera& o = camera.orthographic;
        if (!(std::abs(o.xmag) > 0 && std::abs(o.ymag) > 0 && std::abs(o.ymag) <= kMaxCoordinate &&
              std::abs(o.xmag) <= kMaxCoordinate)) {
            return refuse(at, absl::StrCat("xmag ", o.xmag, " and ymag ", o.ymag,
                                           " must be non-zero and finite"));
        }
        // The rays start on the film plane itself: znear and zfar clip nothing here.
        spec.projection = CameraSpec::Projection::kOrthographic;
        spec.half_height = std::abs(o.ymag);
        aspect = std::abs(o.xmag) / std::abs(o.ymag);
    } else {
        return refuse(at, absl::StrCat("type \"", camera.type,
                                       "\" is unknown; expected perspective or orthographic"));
    }
    if (!(aspect >= 1e-3 && aspect <= 1e3)) {
        return refuse(at, absl::StrCat("aspect ratio ", aspect, " is not within [0.001, 1000]"));
    }
    spec.width =
        aspect >= 1 ? kGltfLongerSide : std::max(1, int(std::lround(kGltfLongerSide * aspect)));
    spec.height =
        aspect >= 1 ? std::max(1, int(std::lround(kGltfLongerSide / aspect))) : kGltfLongerSide;
    cameras_.push_back(std::move(out));
}

void GltfImporter::AddLight(const tinygltf::Value& light_index, const Affine& world,
                            const std::string& where) {
    const std::string at = where + ".extensions.KHR_lights_punctual.light";
    if (!light_index.IsNumber()) Fail(at, "missing or not a number");
    const int index = int(light_index.GetNumberAsDouble());
    if (index < 0 || index >= int(model_.lights.size())) {
        Fail(at, absl::StrCat(index, " is not a light index (the file has ", model_.lights.size(),
                              ")"));
    }
    const tinygltf::Light& light = model_.lights[size_t(index)];
    const std::string light_at =
        absl::StrCat("KHR_lights_punctual.lights[", index, "]", Quoted(light.name));
    Rgb color(1.0f);
    if (!light.color.empty()) {
        if (light.color.size() != 3) Fail(light_at, "color needs 3 numbers");
        for (double c : light.color) {
            if (!(c >= 0 && c <= 1e6)) Fail(light_at, absl::StrCat("color holds ", c));
        }
        color = Rgb(float(light.color[0]), float(light.color[1]), float(light.color[2]));
    }
    if (!(light.intensity >= 0 && light.intensity <= 1e13)) {
        Fail(light_at, absl::StrCat("intensity ", light.intensity, " must be in [0, 1e13]"));
    }
    if (light.range > 0) range_ignored_ = true;
    // KHR_lights_punctual gives candela and lux: at 683 lm/W they are W/sr and W/m^2.
    const Rgb radiometric = color * float(light.intensity / kLumensPerWatt);
    const Vec3d position = world.Apply(Vec3d(0, 0, 0));
    const Vec3d axis = world.ApplyLinear(Vec3d(0, 0, -1));
    // A node scaled to zero (a common way to hide one) leaves spot and directional lights
    // no direction: they light nothing.
    if (light.type != "point" && !(Length(axis) > 0)) {
        Tally(absl::StrCat(light.type, " light under a transform that flattens its axis, skipped"),
              "node", where);
        return;
    }
    if (light.type == "point") {
        scene_.point_lights.push_back({position, radiometric});
    } else if (light.type == "spot") {
        const double inner = light.spot.innerConeAngle, outer = light.spot.outerConeAngle;
        if (!(inner >= 0 && inner < outer && outer <= std::numbers::pi / 2)) {
            Fail(light_at, absl::StrCat("spot cone angles ", inner, " and ", outer,
                                        " must satisfy 0 <= inner < outer <= pi/2"));
        }
        scene_.spot_lights.push_back({position, Normalize(axis), radiometric, inner, outer,
                                      SpotLight::Falloff::kKhrLightsPunctual});
    } else if (light.type == "directional") {
        scene_.directional_lights.push_back({Normalize(axis), radiometric});
    } else {
        Fail(light_at, absl::StrCat("type \"", light.type,
                                    "\" is unknown; expected point, spot or directional"));
    }
}

}  // namespace lf::gltf_internal
