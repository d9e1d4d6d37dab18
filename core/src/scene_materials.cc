#include <array>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/texture_io.h"
#include "scene_parser.h"

namespace lf::scene_internal {
namespace {

// Keys any material may have besides its type's: its emission (docs/scene-format.md, Emission).
constexpr std::array<std::string_view, 6> kEmissionKeys = {
    "emission", "luminance_nits", "power_lm", "color", "temperature_k", "two_sided"};

}  // namespace

Material SceneParser::ParseMaterial(const std::string& name, const Node& n) {
    n.RequireObject();
    Material m;
    m.name = name;
    const Node type = n.Get("type");
    const std::string type_name = type.String();
    if (type_name == "lambert") {
        n.WarnUnknownKeys({"type", "reflectance", "base_color", "base_color_texture"},
                          kEmissionKeys);
        ParseBaseColor(n, m);
    } else if (type_name == "mirror") {
        n.WarnUnknownKeys({"type", "reflectance"}, kEmissionKeys);
        m.type = Material::Type::kMirror;
        m.reflectance = n.Get("reflectance").Color(1);
    } else if (type_name == "glossy") {
        n.WarnUnknownKeys({"type", "distribution", "roughness", "reflectance", "eta", "k"},
                          kEmissionKeys);
        m.type = Material::Type::kGlossy;
        if (const std::optional<Node> distribution = n.Find("distribution")) {
            m.distribution = distribution->OneOf<Material::Distribution>(
                "distribution", {{"ggx", Material::Distribution::kGgx},
                                 {"beckmann", Material::Distribution::kBeckmann}});
        }
        m.roughness = n.Get("roughness").PositiveFloat();
        if (n.Has("eta") || n.Has("k")) {
            if (n.Has("reflectance")) n.Fail("give either reflectance or eta and k, not both");
            m.conductor = true;
            const Node eta = n.Get("eta");
            m.eta = eta.Color(kMaxFloat);
            for (const Node& e : eta.Elements()) {
                if (e.Number() == 0) e.Fail("must be > 0");
            }
            m.k = n.Get("k").Color(kMaxFloat);
        } else {
            m.reflectance = n.Get("reflectance").Color(1);
        }
    } else if (type_name == "dielectric") {
        n.WarnUnknownKeys({"type", "ior"}, kEmissionKeys);
        m.type = Material::Type::kDielectric;
        m.ior = n.Get("ior").PositiveFloat();
    } else if (type_name == "principled") {
        ParsePrincipled(n, m);
    } else if (type_name == "interface") {
        // Neither reflects nor emits: a colour or an emission here is a misunderstanding.
        n.RejectUnknownKeys({"type", "name"},
                            "an interface material (a boundary between media) has no other keys");
        m.type = Material::Type::kInterface;
        return m;
    } else {
        type.Fail(absl::StrCat(
            "unknown material type \"", type_name,
            "\"; expected lambert, mirror, glossy, dielectric, principled or interface"));
    }
    ParseEmission(n, m);
    return m;
}

void SceneParser::ParseEmission(const Node& n, Material& m) {
    if (const std::optional<Node> two_sided = n.Find("two_sided")) {
        m.two_sided_emission = two_sided->Bool();
        if (m.two_sided_emission && !m.VisibleFromBehind()) {
            two_sided->Fail(
                "a single-sided surface (double_sided false) cannot be seen, so cannot emit, "
                "from behind: set double_sided true");
        }
    }
    const std::optional<Strength> strength = FindStrength(n,
                                                          {{"emission", "W m^-2 sr^-1", false},
                                                           {"luminance_nits", "cd/m^2", true},
                                                           {"power_lm", "lm", true}},
                                                          false);
    if (!strength) {
        if (n.Has("color") || n.Has("temperature_k")) {
            n.Fail(
                "color and temperature_k are the emission's colour: give them with emission (a "
                "number), luminance_nits or power_lm (the surface's colour is base_color)");
        }
        if (m.emission_texture.valid()) m.emission = Rgb(1);  // the texture alone
        return;
    }
    if (std::string_view(strength->key.name) != "power_lm") {
        m.emission = StrengthValue(n, *strength);
        return;
    }
    if (m.emission_texture.valid()) {
        strength->value.Fail(
            "cannot spread a power over an emission_texture (its mean over the surface is "
            "unknown); give luminance_nits, which the texture multiplies");
    }
    // Luminance 1 for now; ResolveEmittedPower scales it once the area is known.
    m.emission = LightColor(n, true);
    pending_power_.push_back({material_index_.at(m.name), strength->value});
}

void SceneParser::ParseBaseColor(const Node& n, Material& m) {
    if (n.Has("reflectance") && n.Has("base_color")) {
        n.Fail("give either base_color or reflectance (the same thing), not both");
    }
    if (const std::optional<Node> texture = n.Find("base_color_texture")) {
        m.base_color_texture = ParseTexture(*texture, true);
    }
    const std::string key = n.Has("base_color") ? "base_color" : "reflectance";
    if (n.Has(key) || !m.base_color_texture.valid()) m.reflectance = n.Get(key).Color(1);
    if (!n.Has(key) && m.base_color_texture.valid()) m.reflectance = Rgb(1);
}

void SceneParser::ParsePrincipled(const Node& n, Material& m) {
    n.WarnUnknownKeys({"type",
                       "base_color",
                       "reflectance",
                       "base_color_texture",
                       "metallic",
                       "roughness",
                       "metallic_roughness_texture",
                       "specular",
                       "specular_color",
                       "ior",
                       "transmission",
                       "thickness",
                       "attenuation_color",
                       "attenuation_distance",
                       "clearcoat",
                       "clearcoat_roughness",
                       "sheen_color",
                       "sheen_roughness",
                       "normal_texture",
                       "transmission_texture",
                       "normal_scale",
                       "emission_texture",
                       "opacity",
                       "alpha_mode",
                       "alpha_cutoff",
                       "double_sided"},
                      kEmissionKeys);
    m.type = Material::Type::kPrincipled;
    if (!n.Has("base_color") && !n.Has("reflectance") && !n.Has("base_color_texture")) {
        m.reflectance = Rgb(0.8f);
    } else {
        ParseBaseColor(n, m);
    }
    auto fraction = [&](const char* key, float fallback) {
        const std::optional<Node> value = n.Find(key);
        return value ? float(value->NumberIn(0, 1, "in [0, 1]")) : fallback;
    };
    m.metallic = fraction("metallic", 0);
    m.roughness = fraction("roughness", 0.5f);
    m.specular = fraction("specular", 1);
    if (const std::optional<Node> color = n.Find("specular_color")) {
        m.specular_color = color->Color(kMaxFloat);
    }
    m.transmission = fraction("transmission", 0);
    m.clearcoat = fraction("clearcoat", 0);
    m.clearcoat_roughness = fraction("clearcoat_roughness", 0);
    m.sheen_roughness = fraction("sheen_roughness", 0);
    if (const std::optional<Node> color = n.Find("sheen_color")) m.sheen_color = color->Color(1);
    m.opacity = fraction("opacity", 1);
    m.alpha_cutoff = fraction("alpha_cutoff", 0.5f);
    if (const std::optional<Node> ior = n.Find("ior")) m.ior = ior->PositiveFloat();
    if (const std::optional<Node> thickness = n.Find("thickness")) {
        m.thickness = float(thickness->NumberIn(0, kMaxCoordinate, "≥ 0 (metres)"));
    }
    if (const std::optional<Node> color = n.Find("attenuation_color")) {
        m.attenuation_color = color->Color(1);
    }
    if (const std::optional<Node> distance = n.Find("attenuation_distance")) {
        m.attenuation_distance = distance->PositiveFloat();
    }
    if (const std::optional<Node> texture = n.Find("metallic_roughness_texture")) {
        m.metallic_roughness_texture = ParseTexture(*texture, false);
    }
    if (const std::optional<Node> texture = n.Find("normal_texture")) {
        m.normal_texture = ParseTexture(*texture, false);
    }
    if (const std::optional<Node> texture = n.Find("transmission_texture")) {
        m.transmission_texture = ParseTexture(*texture, false);
    }
    if (const std::optional<Node> scale = n.Find("normal_scale")) {
        m.normal_scale = float(scale->NumberIn(-kMaxFloat, kMaxFloat, "a finite float"));
    }
    if (const std::optional<Node> texture = n.Find("emission_texture")) {
        m.emission_texture = ParseTexture(*texture, true);
    }
    if (const std::optional<Node> mode = n.Find("alpha_mode")) {
        m.alpha_mode = mode->OneOf<Material::AlphaMode>("alpha mode",
                                                        {{"opaque", Material::AlphaMode::kOpaque},
                                                         {"mask", Material::AlphaMode::kMask},
                                                         {"blend", Material::AlphaMode::kBlend}});
    }
    if (const std::optional<Node> sided = n.Find("double_sided")) m.double_sided = sided->Bool();
}

TextureRef SceneParser::ParseTexture(const Node& n, bool srgb) {
    TextureRef ref;
    ref.srgb = srgb;
    if (n.json().is_string()) {
        ref.image = TextureIndex(n.String(), n.path());
        return ref;
    }
    n.ExpectObject({"file", "wrap", "filter", "transform"});
    const Node file = n.Get("file");
    ref.image = TextureIndex(file.String(), file.path());
    if (const std::optional<Node> wrap = n.Find("wrap")) {
        ref.wrap_s = ref.wrap_t = wrap->OneOf<TextureRef::Wrap>(
            "wrap mode", {{"repeat", TextureRef::Wrap::kRepeat},
                          {"clamp", TextureRef::Wrap::kClampToEdge},
                          {"mirror", TextureRef::Wrap::kMirroredRepeat}});
    }
    if (const std::optional<Node> filter = n.Find("filter")) {
        ref.nearest = filter->OneOf<bool>("filter", {{"linear", false}, {"nearest", true}});
    }
    if (const std::optional<Node> transform = n.Find("transform")) {
        transform->ExpectObject({"offset", "rotation_deg", "scale"});
        auto pair = [&](const char* key, Vec2 fallback, bool nonzero) {
            const std::optional<Node> value = transform->Find(key);
            if (!value) return fallback;
            const std::vector<Node> e = value->Elements(2);
            const Vec2 v{float(e[0].Coordinate()), float(e[1].Coordinate())};
            if (nonzero && (v.x == 0 || v.y == 0)) value->Fail("must not be zero");
            return v;
        };
        ref.offset = pair("offset", ref.offset, false);
        ref.scale = pair("scale", ref.scale, true);
        if (const std::optional<Node> rotation = transform->Find("rotation_deg")) {
            ref.rotation = float(rotation->Number() * std::numbers::pi / 180);
        }
    }
    return ref;
}

int SceneParser::TextureIndex(const std::string& name, const std::string& where) {
    const std::string key = std::filesystem::path(name).lexically_normal().string();
    if (const auto found = texture_index_.find(key); found != texture_index_.end()) {
        return found->second;
    }
    textures_->push_back(DecodeFile(name, where));
    return texture_index_[key] = int(textures_->size() - 1);
}

std::shared_ptr<const TextureImage> SceneParser::DecodeFile(const std::string& name,
                                                            const std::string& where) {
    if (name.empty()) throw LoadError{absl::InvalidArgumentError(where + ": empty file name")};
    absl::StatusOr<std::string> bytes = read_file_(name);
    if (!bytes.ok()) {
        throw LoadError{
            absl::Status(bytes.status().code(),
                         absl::StrCat(where, " \"", name, "\": ", bytes.status().message()))};
    }
    hash_.Update(*bytes);
    absl::StatusOr<std::shared_ptr<const TextureImage>> image = DecodeTexture(*bytes, name);
    if (!image.ok()) {
        throw LoadError{absl::Status(image.status().code(),
                                     absl::StrCat(where, ": ", image.status().message()))};
    }
    return *std::move(image);
}

}  // namespace lf::scene_internal
