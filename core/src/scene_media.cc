#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/volume_grid.h"
#include "scene_parser.h"

namespace lf::scene_internal {

void SceneParser::ParseMedia(const Node& media, Scene& scene) {
    media.RequireObject();
    for (const auto& [name, value] : media.json().items()) {
        medium_index_[name] = int(scene.media.size());
        scene.media.push_back(
            ParseMedium(name, Node(value, absl::StrCat(media.path(), ".", name), &warnings_)));
    }
}

Medium SceneParser::ParseMedium(const std::string& name, const Node& n) {
    n.RequireObject();
    Medium m;
    m.name = name;
    m.type = n.Get("type").OneOf<Medium::Type>(
        "medium type",
        {{"homogeneous", Medium::Type::kHomogeneous}, {"grid", Medium::Type::kGrid}});
    // Unknown keys are errors: a misspelt coefficient would leave the medium silently empty.
    if (m.type == Medium::Type::kHomogeneous) {
        n.RejectUnknownKeys({"type", "sigma_a", "sigma_s", "scale", "g", "emission"},
                            "a homogeneous medium has type, sigma_a, sigma_s, scale, g and "
                            "emission");
    } else {
        n.RejectUnknownKeys(
            {"type", "file", "density_grid", "sigma_a", "sigma_s", "scale", "g", "emission",
             "emission_grid", "temperature_grid", "temperature_scale", "transform"},
            "a grid medium has type, file, density_grid, sigma_a, sigma_s, scale, "
            "g, emission, emission_grid, temperature_grid, temperature_scale and "
            "transform");
    }
    if (const std::optional<Node> a = n.Find("sigma_a")) m.sigma_a = a->Color(kMaxFloat);
    if (const std::optional<Node> s = n.Find("sigma_s")) m.sigma_s = s->Color(kMaxFloat);
    if (const std::optional<Node> scale = n.Find("scale")) {
        const float k = float(scale->NumberIn(0, kMaxFloat, "≥ 0 and below 3.4e38"));
        m.sigma_a = m.sigma_a * k;
        m.sigma_s = m.sigma_s * k;
        for (int c = 0; c < 3; ++c) {
            if (!std::isfinite(m.sigma_a[c]) || !std::isfinite(m.sigma_s[c])) {
                scale->Fail("sigma_a or sigma_s times scale exceeds the float range");
            }
        }
    }
    if (const std::optional<Node> g = n.Find("g")) {
        m.g = float(g->Number());
        if (!(std::abs(m.g) < 1)) g->Fail(absl::StrCat("must be in (-1, 1), got ", g->Number()));
    }
    if (const std::optional<Node> emission = n.Find("emission")) {
        m.emission = emission->Color(kMaxFloat);
    }
    if (m.type == Medium::Type::kHomogeneous) return m;

    const Node file = n.Get("file");
    const Affine transform = n.Has("transform") ? ParseTransform(n.Get("transform")) : Affine();
    const std::optional<Node> density = n.Find("density_grid");
    m.density = LoadGrid(file, density ? *density : file, density ? density->String() : "density",
                         transform);
    if (const std::optional<Node> emission_grid = n.Find("emission_grid")) {
        m.emission_grid = LoadGrid(file, *emission_grid, emission_grid->String(), transform);
    }
    if (const std::optional<Node> temperature = n.Find("temperature_grid")) {
        m.temperature = LoadGrid(file, *temperature, temperature->String(), transform);
    }
    if (const std::optional<Node> scale = n.Find("temperature_scale")) {
        m.temperature_scale = scale->NumberIn(0, kMaxFloat, "≥ 0 and below 3.4e38");
    }
    return m;
}

std::shared_ptr<const VolumeGrid> SceneParser::LoadGrid(const Node& file, const Node& key,
                                                        const std::string& grid_name,
                                                        const Affine& transform) {
    const std::string name = file.String();
    if (name.empty()) file.Fail("empty file name");
    // Keyed by the name as written, as mesh files are: the same content hash on the farm.
    const std::string normal = std::filesystem::path(name).lexically_normal().string();
    auto cached = grid_files_.find(normal);
    if (cached == grid_files_.end()) {
        absl::StatusOr<std::string> bytes = read_file_(name);
        if (!bytes.ok()) {
            throw LoadError{absl::Status(
                bytes.status().code(),
                absl::StrCat(file.path(), " \"", name, "\": ", bytes.status().message()))};
        }
        hash_.Update(*bytes);
        cached = grid_files_.emplace(normal, *std::move(bytes)).first;
    }
    absl::StatusOr<std::shared_ptr<const VolumeGrid>> grid =
        LoadVolumeGrid(cached->second, name, grid_name, transform);
    if (!grid.ok()) {
        throw LoadError{absl::Status(grid.status().code(),
                                     absl::StrCat(key.path(), ": ", grid.status().message()))};
    }
    return *std::move(grid);
}

int SceneParser::MediumIndex(const Node& n) const {
    const std::string name = n.String();
    const auto found = medium_index_.find(name);
    if (found != medium_index_.end()) return found->second;
    std::vector<std::string> names;
    for (const auto& [known, index] : medium_index_) {
        names.push_back(absl::StrCat("\"", known, "\""));
    }
    n.Fail(absl::StrCat("unknown medium \"", name, "\"; ",
                        names.empty()
                            ? "the scene has no \"media\""
                            : absl::StrCat("the scene's media are ", absl::StrJoin(names, ", "))));
}

MediumInterface SceneParser::ParseMediumInterface(const Node& shape) const {
    MediumInterface media;
    if (const std::optional<Node> interior = shape.Find("interior")) {
        media.has_interface = true;
        media.interior = MediumIndex(*interior);
    }
    if (const std::optional<Node> exterior = shape.Find("exterior")) {
        media.has_interface = true;
        media.exterior = MediumIndex(*exterior);
    }
    return media;
}

}  // namespace lf::scene_internal

namespace lf {

void AddAttenuationMedia(Scene& scene) {
    std::map<int, int> medium_of;  // by material
    auto interior = [&](int material) {
        const Material& m = scene.materials[size_t(material)];
        if (!m.HasInterior() || !std::isfinite(m.attenuation_distance)) return -1;
        const auto [it, added] = medium_of.emplace(material, int(scene.media.size()));
        if (!added) return it->second;
        Medium& medium = scene.media.emplace_back();
        medium.name = absl::StrCat(m.name, " (volume attenuation)");
        for (int c = 0; c < 3; ++c) {
            // A channel of colour 0 absorbs everything: finite, as the kernels need.
            medium.sigma_a[c] = float(-std::log(std::max(double(m.attenuation_color[c]), 1e-30)) /
                                      m.attenuation_distance);
        }
        return it->second;
    };
    auto attach = [&](int material, MediumInterface& media) {
        if (media.has_interface) return;
        // Outside: the medium the camera is in (the scene's air, vacuum or fog), so a glass in
        // fog leaves a ray in the fog; a shape's own "exterior" says otherwise.
        if (const int medium = interior(material); medium >= 0) {
            media = {true, medium, scene.camera_medium};
        }
    };
    for (TriangleMesh& mesh : scene.meshes) attach(mesh.material, mesh.media);
    for (Sphere& sphere : scene.spheres) attach(sphere.material, sphere.media);
}

}  // namespace lf
