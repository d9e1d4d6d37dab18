#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gltf_importer.h"

namespace lf::gltf_internal {

int GltfImporter::Material(int index, const std::string& where) {
    if (index >= int(model_.materials.size())) {
        Fail(where, absl::StrCat("material ", index, " does not exist"));
    }
    const auto found = material_of_.find(index);
    if (found != material_of_.end()) return found->second;
    lf::Material m = index < 0 ? DefaultMaterial() : ConvertMaterial(index);
    const int scene_index = int(scene_.materials.size());
    scene_.materials.push_back(std::move(m));
    material_of_[index] = scene_index;
    return scene_index;
}

lf::Material GltfImporter::DefaultMaterial() const {
    lf::Material m;
    m.name = absl::StrCat(name_, "#default material");
    m.type = lf::Material::Type::kPrincipled;
    m.reflectance = Rgb(1.0f);
    m.metallic = 1;
    m.roughness = 1;
    m.double_sided = false;
    return m;
}

double GltfImporter::Number(const tinygltf::Value& object, const char* key, double fallback,
                            double lo, double hi, const std::string& where) {
    if (!object.Has(key)) return fallback;
    const tinygltf::Value& v = object.Get(key);
    if (!v.IsNumber()) Fail(where, absl::StrCat(key, " is not a number"));
    const double x = v.GetNumberAsDouble();
    if (!(x >= lo && x <= hi)) {
        Fail(where, absl::StrCat(key, " ", x, " is outside [", lo, ", ", hi, "]"));
    }
    return x;
}

std::vector<double> GltfImporter::Numbers(const tinygltf::Value& object, const char* key,
                                          std::vector<double> fallback, const std::string& where) {
    if (!object.Has(key)) return fallback;
    const tinygltf::Value& v = object.Get(key);
    if (!v.IsArray() || v.ArrayLen() != fallback.size()) {
        Fail(where, absl::StrCat(key, " must be an array of ", fallback.size(), " numbers"));
    }
    for (size_t i = 0; i < fallback.size(); ++i) {
        const tinygltf::Value& e = v.Get(int(i));
        if (!e.IsNumber() || !std::isfinite(e.GetNumberAsDouble())) {
            Fail(where, absl::StrCat(key, "[", i, "] is not a finite number"));
        }
        fallback[i] = e.GetNumberAsDouble();
    }
    return fallback;
}

Rgb GltfImporter::Color(const std::vector<double>& v, const std::string& where, const char* key) {
    for (double c : v) {
        if (!(c >= 0 && c <= 1)) Fail(where, absl::StrCat(key, " holds ", c, ", not in [0, 1]"));
    }
    return Rgb(float(v[0]), float(v[1]), float(v[2]));
}

const tinygltf::Value* GltfImporter::Extension(const tinygltf::ExtensionMap& map, const char* key) {
    const auto found = map.find(key);
    return found == map.end() ? nullptr : &found->second;
}

lf::Material GltfImporter::ConvertMaterial(int index) {
    const tinygltf::Material& g = model_.materials[size_t(index)];
    const std::string where = absl::StrCat("materials[", index, "]", Quoted(g.name));
    lf::Material m;
    m.name = g.name.empty() ? absl::StrCat(name_, "#", where) : g.name;
    m.type = lf::Material::Type::kPrincipled;
    const tinygltf::PbrMetallicRoughness& pbr = g.pbrMetallicRoughness;
    if (pbr.baseColorFactor.size() != 4) Fail(where, "baseColorFactor needs 4 numbers");
    m.reflectance = Color(pbr.baseColorFactor, where, "baseColorFactor");
    m.opacity = float(pbr.baseColorFactor[3]);
    if (!(m.opacity >= 0 && m.opacity <= 1)) Fail(where, "baseColorFactor alpha not in [0, 1]");
    if (!(pbr.metallicFactor >= 0 && pbr.metallicFactor <= 1)) {
        Fail(where, absl::StrCat("metallicFactor ", pbr.metallicFactor, " not in [0, 1]"));
    }
    if (!(pbr.roughnessFactor >= 0 && pbr.roughnessFactor <= 1)) {
        Fail(where, absl::StrCat("roughnessFactor ", pbr.roughnessFactor, " not in [0, 1]"));
    }
    m.metallic = float(pbr.metallicFactor);
    m.roughness = float(pbr.roughnessFactor);
    m.base_color_texture = Texture(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
                                   pbr.baseColorTexture.extensions, true,
                                   where + ".pbrMetallicRoughness.baseColorTexture");
    m.metallic_roughness_texture =
        Texture(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                pbr.metallicRoughnessTexture.extensions, false,
                where + ".pbrMetallicRoughness.metallicRoughnessTexture");
    m.normal_texture = Texture(g.normalTexture.index, g.normalTexture.texCoord,
                               g.normalTexture.extensions, false, where + ".normalTexture");
    m.normal_scale = float(g.normalTexture.scale);
    if (!std::isfinite(m.normal_scale)) Fail(where, "normalTexture.scale is not finite");
    if (g.occlusionTexture.index >= 0) {
        Tally("occlusionTexture ignored (a path tracer computes occlusion itself)", "material",
              where);
    }
    m.emission_texture = Texture(g.emissiveTexture.index, g.emissiveTexture.texCoord,
                                 g.emissiveTexture.extensions, true, where + ".emissiveTexture");
    if (g.emissiveFactor.size() != 3) Fail(where, "emissiveFactor needs 3 numbers");
    Rgb emission = Color(g.emissiveFactor, where, "emissiveFactor");
    if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_emissive_strength")) {
        emission = emission * float(Number(*e, "emissiveStrength", 1, 0, 1e10,
                                           where + ".KHR_materials_emissive_strength"));
    }
    m.emission = emission;
    if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_ior")) {
        m.ior = float(Number(*e, "ior", 1.5, 1, 10, where + ".KHR_materials_ior"));
        // ior 0 means "no Fresnel" in the extension; we cannot render that.
    }
    if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_transmission")) {
        const std::string at = where + ".KHR_materials_transmission";
        m.transmission = float(Number(*e, "transmissionFactor", 0, 0, 1, at));
        m.transmission_texture = TextureInfo(*e, "transmissionTexture", false, at);
    }
    if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_volume")) {
        const std::string at = where + ".KHR_materials_volume";
        m.thickness = float(Number(*e, "thicknessFactor", 0, 0, 1e15, at));
        m.attenuation_distance =
            float(Number(*e, "attenuationDistance", std::numeric_limits<double>::infinity(), 0,
                         std::numeric_limits<double>::infinity(), at));
        if (!(m.attenuation_distance > 0)) Fail(at, "attenuationDistance must be above 0");
        // The extension gives it in the file's world space; a JSON scene that includes the
        // file scales that space by its transform (a uniform scale's factor; the mean one
        // of an anisotropic scale).
        m.attenuation_distance *= float(std::cbrt(std::abs(options_.transform.Determinant())));
        m.attenuation_color =
            Color(Numbers(*e, "attenuationColor", {1, 1, 1}, at), at, "attenuationColor");
        if (e->Has("thicknessTexture")) {
            // The extension's thickness stands in for the geometry in rasterisers; a ray
            // tracer measures the path inside, so only thin (0) against solid matters here.
            Tally(
                "KHR_materials_volume thicknessTexture unused (paths inside are measured on "
                "the geometry)",
                "material", where);
        }
    }
    if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_clearcoat")) {
        const std::string at = where + ".KHR_materials_clearcoat";
        m.clearcoat = float(Number(*e, "clearcoatFactor", 0, 0, 1, at));
        m.clearcoat_roughness = float(Number(*e, "clearcoatRoughnessFactor", 0, 0, 1, at));
        m.clearcoat_texture = TextureInfo(*e, "clearcoatTexture", false, at);
        m.clearcoat_roughness_texture = TextureInfo(*e, "clearcoatRoughnessTexture", false, at);
        m.clearcoat_normal_texture = TextureInfo(*e, "clearcoatNormalTexture", false, at);
        if (e->Has("clearcoatNormalTexture")) {
            m.clearcoat_normal_scale = float(Number(e->Get("clearcoatNormalTexture"), "scale", 1,
                                                    -1e6, 1e6, at + ".clearcoatNormalTexture"));
        }
    }
    if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_sheen")) {
        const std::string at = where + ".KHR_materials_sheen";
        m.sheen_color =
            Color(Numbers(*e, "sheenColorFactor", {0, 0, 0}, at), at, "sheenColorFactor");
        m.sheen_roughness = float(Number(*e, "sheenRoughnessFactor", 0, 0, 1, at));
        m.sheen_color_texture = TextureInfo(*e, "sheenColorTexture", true, at);
        m.sheen_roughness_texture = TextureInfo(*e, "sheenRoughnessTexture", false, at);
    }
    if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_specular")) {
        const std::string at = where + ".KHR_materials_specular";
        m.specular = float(Number(*e, "specularFactor", 1, 0, 1, at));
        m.specular_texture = TextureInfo(*e, "specularTexture", false, at);
        // Unbounded above: min(F0 colour, 1) applies per channel when rendering.
        const std::vector<double> tint = Numbers(*e, "specularColorFactor", {1, 1, 1}, at);
        for (size_t c = 0; c < 3; ++c) {
            if (!(tint[c] >= 0 && tint[c] <= 1e10)) {
                Fail(at, absl::StrCat("specularColorFactor[", c, "] ", tint[c],
                                      " is outside [0, 1e10]"));
            }
        }
        m.specular_color = Rgb(float(tint[0]), float(tint[1]), float(tint[2]));
        m.specular_color_texture = TextureInfo(*e, "specularColorTexture", true, at);
    }
    m.double_sided = g.doubleSided;
    if (Extension(g.extensions, "KHR_materials_unlit")) MakeUnlit(m);
    if (g.alphaMode == "MASK") {
        m.alpha_mode = lf::Material::AlphaMode::kMask;
        m.alpha_cutoff = float(g.alphaCutoff);
        if (!(m.alpha_cutoff >= 0)) Fail(where, "alphaCutoff must be at least 0");
    } else if (g.alphaMode == "BLEND") {
        m.alpha_mode = lf::Material::AlphaMode::kBlend;
    } else if (g.alphaMode != "OPAQUE") {
        Fail(where, absl::StrCat("alphaMode \"", g.alphaMode,
                                 "\" is unknown; expected OPAQUE, MASK or BLEND"));
    }
    return m;
}

void GltfImporter::MakeUnlit(lf::Material& m) {
    // KHR_materials_unlit: the base colour is the radiance the surface shows, and nothing is
    // reflected; vertex colours multiply it as they did the base colour. The base colour
    // texture stays for its alpha (cut-outs, blending).
    m.type = lf::Material::Type::kLambert;
    m.emission = m.reflectance;
    m.emission_texture = m.base_color_texture;
    m.two_sided_emission = m.double_sided;
    m.emission_by_vertex_color = true;
    m.reflectance = Rgb(0.0f);
}

TextureRef GltfImporter::Texture(int index, int tex_coord, const tinygltf::ExtensionMap& extensions,
                                 bool srgb, const std::string& where) {
    TextureRef ref;
    if (index < 0) return ref;
    if (index >= int(model_.textures.size())) {
        Fail(where, absl::StrCat("texture ", index, " does not exist"));
    }
    const tinygltf::Texture& texture = model_.textures[size_t(index)];
    const std::string at = absl::StrCat("textures[", index, "]", Quoted(texture.name));
    if (texture.source < 0 || texture.source >= int(model_.images.size())) {
        Fail(at, absl::StrCat("source ", texture.source, " is not an image"));
    }
    ref.image = Image(texture.source);
    ref.srgb = srgb;
    if (texture.sampler >= 0) {
        if (texture.sampler >= int(model_.samplers.size())) {
            Fail(at, absl::StrCat("sampler ", texture.sampler, " does not exist"));
        }
        const tinygltf::Sampler& s = model_.samplers[size_t(texture.sampler)];
        ref.wrap_s = Wrap(s.wrapS, at);
        ref.wrap_t = Wrap(s.wrapT, at);
        ref.nearest = s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
    }
    if (const tinygltf::Value* t = Extension(extensions, "KHR_texture_transform")) {
        const std::string t_at = where + ".KHR_texture_transform";
        const std::vector<double> offset = Numbers(*t, "offset", {0, 0}, t_at);
        const std::vector<double> scale = Numbers(*t, "scale", {1, 1}, t_at);
        ref.offset = {float(offset[0]), float(offset[1])};
        ref.scale = {float(scale[0]), float(scale[1])};
        ref.rotation = float(Number(*t, "rotation", 0, -1e6, 1e6, t_at));
        if (t->Has("texCoord")) {
            tex_coord = int(Number(*t, "texCoord", 0, 0, 1e6, t_at));
        }
    }
    if (tex_coord < 0) Fail(where, absl::StrCat("texCoord ", tex_coord, " is negative"));
    if (tex_coord > 1) {
        Warn(absl::StrCat(where, ": uses TEXCOORD_", tex_coord,
                          "; lightfarm reads TEXCOORD_0 and TEXCOORD_1 only and uses TEXCOORD_0"));
    } else {
        ref.tex_coord = tex_coord;
    }
    return ref;
}

TextureRef GltfImporter::TextureInfo(const tinygltf::Value& extension, const char* key, bool srgb,
                                     const std::string& where) {
    if (!extension.Has(key)) return {};
    const std::string at = absl::StrCat(where, ".", key);
    const tinygltf::Value& info = extension.Get(key);
    if (!info.IsObject()) Fail(at, "is not an object");
    if (!info.Has("index")) Fail(at, "has no index");
    tinygltf::ExtensionMap extensions;
    if (info.Has("extensions")) {
        const tinygltf::Value& e = info.Get("extensions");
        for (const std::string& name : e.Keys()) extensions[name] = e.Get(name);
    }
    return Texture(int(Number(info, "index", 0, 0, 1e9, at)),
                   int(Number(info, "texCoord", 0, 0, 1e6, at)), extensions, srgb, at);
}

TextureRef::Wrap GltfImporter::Wrap(int mode, const std::string& where) {
    switch (mode) {
        case TINYGLTF_TEXTURE_WRAP_REPEAT:
            return TextureRef::Wrap::kRepeat;
        case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE:
            return TextureRef::Wrap::kClampToEdge;
        case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT:
            return TextureRef::Wrap::kMirroredRepeat;
        default:
            Fail(where, absl::StrCat("sampler wrap mode ", mode, " is unknown"));
    }
}

int GltfImporter::Image(int index) {
    if (const auto found = texture_of_.find(index); found != texture_of_.end()) {
        return found->second;
    }
    const tinygltf::Image& image = model_.images[size_t(index)];
    const std::string where = absl::StrCat("images[", index, "]", Quoted(image.name));
    const auto decoded = images_.find(index);
    if (decoded == images_.end()) {
        // tinygltf only warns when an image file cannot be read; here it is an error.
        const auto read = read_errors_.find(image.uri);
        Fail(where, read != read_errors_.end()
                        ? absl::StrCat("uri \"", image.uri, "\": ", read->second.message())
                        : absl::StrCat("uri \"", image.uri, "\" could not be loaded"));
    }
    if (!decoded->second.ok()) Fail(where, std::string(decoded->second.status().message()));
    const int texture = int(scene_.textures.size());
    scene_.textures.push_back(*decoded->second);
    texture_of_[index] = texture;
    return texture;
}

}  // namespace lf::gltf_internal
