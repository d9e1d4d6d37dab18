#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/blackbody.h"
#include "lf/core/photometry.h"
#include "lf/core/sky_option.h"
#include "lf/core/texture.h"
#include "scene_parser.h"

namespace lf::scene_internal {
namespace {

// Emitted radiance (W m^-2 sr^-1) and point-light intensity (W/sr): 500 times the sun's
// radiance. Far above it, a light's power overflows float in the light sampler and samples
// reach the film's clamp (1e15, film.cc), both silently wrong.
constexpr float kMaxRadiance = 1e10f;

}  // namespace

void SceneParser::ParseLight(const Node& n, Scene& scene) {
    n.RequireObject();
    const Node type = n.Get("type");
    const std::string type_name = type.String();
    if (type_name == "point") {
        n.WarnUnknownKeys({"type", "position", "intensity", "power", "intensity_cd", "power_lm",
                           "color", "temperature_k"});
        scene.point_lights.push_back(
            {n.Get("position").Vector(), RadiantIntensity(n, 4 * std::numbers::pi)});
    } else if (type_name == "spot") {
        scene.spot_lights.push_back(ParseSpot(n));
    } else if (type_name == "directional") {
        n.WarnUnknownKeys({"type", "direction", "irradiance", "illuminance_lux", "color",
                           "temperature_k", "angular_diameter_deg"});
        DirectionalLight light;
        light.direction = Direction(n.Get("direction"));
        light.irradiance = StrengthValue(
            n, *FindStrength(n, {{"irradiance", "W/m^2", false}, {"illuminance_lux", "lx", true}},
                             true));
        if (const std::optional<Node> diameter = n.Find("angular_diameter_deg")) {
            light.angular_diameter =
                diameter->NumberIn(0, 90, "in [0, 90] degrees") * std::numbers::pi / 180;
        }
        scene.directional_lights.push_back(light);
    } else if (type_name == "environment") {
        if (scene.environment) {
            n.Fail(absl::StrCat("a second environment light (the first is ", environment_path_,
                                "): a scene has at most one sky"));
        }
        environment_path_ = n.path();
        scene.environment = ParseEnvironment(n);
    } else {
        type.Fail(absl::StrCat("unknown light type \"", type_name,
                               "\"; expected point, spot, directional or environment"));
    }
}

SpotLight SceneParser::ParseSpot(const Node& n) {
    // inner_cone_deg and outer_cone_deg: the names before issue 13, still read.
    n.WarnUnknownKeys({"type", "position", "direction", "intensity", "power", "intensity_cd",
                       "power_lm", "color", "temperature_k", "inner_angle_deg", "outer_angle_deg",
                       "inner_cone_deg", "outer_cone_deg"});
    SpotLight light;
    light.falloff = SpotLight::Falloff::kSmoothstep;
    light.position = n.Get("position").Vector();
    light.direction = Direction(n.Get("direction"));
    auto angle = [&](const char* key, const char* alias) -> std::optional<Node> {
        if (n.Has(key) && n.Has(alias)) {
            n.Fail(absl::StrCat("give ", key, " or its older name ", alias, ", not both"));
        }
        return n.Has(key) ? n.Find(key) : n.Find(alias);
    };
    const std::optional<Node> inner = angle("inner_angle_deg", "inner_cone_deg");
    const std::optional<Node> outer = angle("outer_angle_deg", "outer_cone_deg");
    const double inner_deg = inner ? inner->NumberIn(0, 90, "in [0, 90) degrees") : 0;
    const double outer_deg = outer ? outer->NumberIn(0, 90, "in (0, 90] degrees") : 45;
    if (!(inner_deg < outer_deg)) {
        const std::string fade = ": the light fades out between the two cones";
        if (!outer) {
            inner->Fail(absl::StrCat(inner_deg, " must be below the default outer_angle_deg (",
                                     outer_deg, ")", fade));
        }
        outer->Fail(absl::StrCat(outer_deg, " must be above ",
                                 inner ? inner->path() : "the default inner_angle_deg", " (",
                                 inner_deg, ")", fade));
    }
    light.inner_cone = inner_deg * std::numbers::pi / 180;
    light.outer_cone = outer_deg * std::numbers::pi / 180;
    // The smoothstep falloff's solid angle: the inner cone, 2 pi (1 - cos inner), plus the
    // band between the cones, where smoothstep of cos averages exactly 1/2 (s(t) + s(1 - t)
    // = 1), 2 pi (cos inner - cos outer) / 2.
    const double cos_inner = std::cos(light.inner_cone);
    const double cos_outer = std::cos(light.outer_cone);
    light.intensity = RadiantIntensity(n, 2 * std::numbers::pi * (1 - (cos_inner + cos_outer) / 2));
    return light;
}

EnvironmentLight SceneParser::ParseEnvironment(const Node& n) {
    n.WarnUnknownKeys({"type", "radiance", "luminance_nits", "file", "scale", "rotate_y_deg",
                       "color", "temperature_k"});
    EnvironmentLight light;
    if (const std::optional<Node> rotate = n.Find("rotate_y_deg")) {
        light.rotate_y =
            rotate->NumberIn(-1e6, 1e6, "within ±1e6 degrees") * std::numbers::pi / 180;
    }
    const std::optional<Node> file = n.Find("file");
    const std::optional<Node> scale_node = n.Find("scale");
    const double scale =
        scale_node ? scale_node->NumberIn(0, kMaxRadiance, "≥ 0 and at most 1e10") : 1;
    const std::optional<Strength> strength = FindStrength(
        n, {{"radiance", "W m^-2 sr^-1", false}, {"luminance_nits", "cd/m^2", true}}, !file);
    const bool photometric = strength && strength->key.photometric;
    if (photometric && scale_node) {
        scale_node->Fail("luminance_nits sets the sky's strength already; give one of the two");
    }
    // A map's texels are not bounded here; its factor, like a uniform sky, is.
    const auto checked = [&]() {
        if (!(light.radiance.MaxComponent() <= kMaxRadiance)) {
            n.Fail("too bright: the sky's radiance (or a map's factor) is over 1e10");
        }
        return light;
    };
    if (!file) {
        light.radiance = StrengthValue(n, *strength) * float(scale);
        return checked();
    }
    if (strength && !photometric) {
        strength->value.Fail(
            "a uniform sky's radiance; with a file the map's texels are the radiance (scale, "
            "color or temperature_k multiply them)");
    }
    const std::string name = file->String();
    light.map = DecodeSkyMap(name, file->path());
    const Rgb tint = LightColor(n, photometric);
    if (!photometric) {
        light.radiance = tint * float(scale);
    } else {
        const double mean = MeanLuminance(*light.map, tint);
        if (!(mean > 0)) {
            file->Fail(absl::StrCat("\"", name, "\" is black: luminance_nits cannot scale it"));
        }
        const double nits =
            strength->value.NumberIn(0, kLumensPerWatt * kMaxRadiance, "≥ 0 and at most 6.8e12");
        light.radiance = tint * float(nits / (kLumensPerWatt * mean));
    }
    return checked();
}

std::shared_ptr<const TextureImage> SceneParser::DecodeSkyMap(const std::string& name,
                                                              const std::string& where) {
    std::shared_ptr<const TextureImage> map = DecodeFile(name, where);
    if (!map->hdr) {
        throw LoadError{absl::InvalidArgumentError(
            absl::StrCat(where, ": \"", name,
                         "\" is an 8- or 16-bit image of display values, not radiance; give a "
                         "Radiance HDR or OpenEXR map"))};
    }
    return map;
}

void SceneParser::ApplySky(Scene& scene) {
    absl::StatusOr<SkyOption> sky = ParseSkyOption(options_.sky);
    if (!sky.ok()) throw LoadError{sky.status()};
    // The flag changes the render as a scene file would: it counts in the content hash.
    hash_.Update(absl::StrCat("--sky ", options_.sky));
    if (scene.environment) warnings_.push_back("--sky replaces the scene's environment light");
    EnvironmentLight light;
    light.radiance = sky->radiance;
    if (!sky->file.empty()) light.map = DecodeSkyMap(sky->file, "--sky");
    scene.environment = light;
}

double SceneParser::MeanLuminance(const TextureImage& map, const Rgb& tint) {
    double sum = 0;
    for (int y = 0; y < map.height; ++y) {
        double row = 0;
        for (int x = 0; x < map.width; ++x) {
            // Cleaned as the renderer cleans it (EmittableRadiance), so that the mean is
            // that of the light it will emit.
            row += EmittableRadiance(Texel(map, x, y, false).rgb * tint).Luminance();
        }
        const double weight = std::cos(std::numbers::pi * y / map.height) -
                              std::cos(std::numbers::pi * (y + 1) / map.height);
        sum += weight * row / map.width;
    }
    return sum / 2;  // the weights sum to 2 (the sphere's 4 pi over 2 pi)
}

Vec3d SceneParser::Direction(const Node& n) {
    const Vec3d v = n.Vector();
    if (LengthSquared(v) == 0) n.Fail("must not be zero");
    return Normalize(v);
}

std::optional<SceneParser::Strength> SceneParser::FindStrength(
    const Node& n, std::initializer_list<StrengthKey> keys, bool required) {
    std::optional<Strength> found;
    bool radiometric = false, photometric = false;
    int given = 0;
    for (const StrengthKey& key : keys) {
        if (std::optional<Node> value = n.Find(key.name)) {
            found.emplace(Strength{key, *value});
            (key.photometric ? photometric : radiometric) = true;
            ++given;
        }
    }
    if (given == 1 || (given == 0 && !required)) return found;
    auto list = [&](std::optional<bool> photometric_only) {
        std::vector<std::string> names;
        for (const StrengthKey& key : keys) {
            if (photometric_only && key.photometric != *photometric_only) continue;
            names.push_back(photometric_only ? std::string(key.name)
                                             : absl::StrCat(key.name, " (", key.unit, ")"));
        }
        std::string text;
        for (size_t i = 0; i < names.size(); ++i) {
            text += absl::StrCat(i == 0 ? "" : i + 1 == names.size() ? " or " : ", ", names[i]);
        }
        return text;
    };
    if (radiometric && photometric) {
        n.Fail(absl::StrCat("give a radiometric strength (", list(false),
                            ") or a photometric one (", list(true), "), not both"));
    }
    n.Fail(absl::StrCat("give exactly one of ", list(std::nullopt)));
}

Rgb SceneParser::StrengthValue(const Node& light, const Strength& strength) {
    const Node& value = strength.value;
    const float divisor = float(strength.key.divisor);
    if (!strength.key.photometric && value.json().is_array()) {
        if (light.Has("color") || light.Has("temperature_k")) {
            value.Fail(
                "an [r, g, b] strength is a colour itself; with color or temperature_k give a "
                "number");
        }
        return value.Color(divisor * kMaxRadiance) / divisor;
    }
    const double per_watt = strength.key.photometric ? kLumensPerWatt : 1;
    const double v =
        value.NumberIn(0, per_watt * divisor * kMaxRadiance,
                       absl::StrCat("≥ 0 and at most ", per_watt * divisor * kMaxRadiance));
    const Rgb radiometric =
        LightColor(light, strength.key.photometric) * float(v / per_watt / divisor);
    if (!(radiometric.MaxComponent() <= kMaxRadiance)) {
        value.Fail("too bright: a channel is over 1e10 (500 times the sun's radiance)");
    }
    return radiometric;
}

Rgb SceneParser::RadiantIntensity(const Node& n, double solid_angle) {
    return StrengthValue(n, *FindStrength(n,
                                          {{"intensity", "W/sr", false},
                                           {"power", "W", false, solid_angle},
                                           {"intensity_cd", "cd", true},
                                           {"power_lm", "lm", true, solid_angle}},
                                          true));
}

Rgb SceneParser::LightColor(const Node& light, bool photometric) {
    if (light.Has("color") && light.Has("temperature_k")) {
        light.Fail("give color or temperature_k, not both");
    }
    if (const std::optional<Node> kelvin = light.Find("temperature_k")) {
        return BlackbodyRgb(
            kelvin->NumberIn(kMinBlackbodyK, kMaxBlackbodyK, "in [1000, 40000] kelvin"));
    }
    const std::optional<Node> color = light.Find("color");
    if (!color) return Rgb(1);
    const Rgb c = color->Color(1);
    if (!photometric) return c;
    if (!(c.Luminance() > 0)) {
        color->Fail("has luminance 0: a photometric strength cannot give it any light");
    }
    return c / c.Luminance();
}

void SceneParser::ResolveEmittedPower(Scene& scene) {
    for (const PendingPower& pending : pending_power_) {
        double area = 0;
        for (const TriangleMesh& mesh : scene.meshes) {
            if (mesh.material != pending.material) continue;
            for (const std::array<uint32_t, 3>& t : mesh.triangles) {
                const Vec3d& a = mesh.positions[t[0]];
                area += Length(Cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a)) / 2;
            }
        }
        for (const Sphere& sphere : scene.spheres) {
            if (sphere.material == pending.material) {
                area += 4 * std::numbers::pi * sphere.radius * sphere.radius;
            }
        }
        if (!(area > 0)) {
            pending.value.Fail("no shape uses this material: the power has no area to leave");
        }
        Material& m = scene.materials[size_t(pending.material)];
        const double lumens = pending.value.NumberIn(0, kMaxFloat, "≥ 0 (lumens)");
        const double faces = m.two_sided_emission ? 2 : 1;
        const double nits = lumens / (faces * std::numbers::pi * area);
        m.emission *= float(nits / kLumensPerWatt);
        if (!(m.emission.MaxComponent() <= kMaxRadiance)) {
            pending.value.Fail(absl::StrCat("too bright: ", nits,
                                            " cd/m^2 over the material's area of ", area,
                                            " is over 1e10 W m^-2 sr^-1"));
        }
    }
}

}  // namespace lf::scene_internal
