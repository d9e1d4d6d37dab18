// glTF 2.0 files for tests and benchmarks, made in memory: the JSON as nlohmann::json for the
// test to fill in (nodes, meshes, materials...), and one binary buffer the accessors read,
// written out as a .gltf with a separate .bin, a .gltf with a base64 data URI, or a .glb.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "absl/strings/escaping.h"

namespace lf::testing {

class GltfBuilder {
  public:
    static constexpr int kFloat = 5126, kUnsignedShort = 5123, kUnsignedInt = 5125;

    GltfBuilder() { json_ = {{"asset", {{"version", "2.0"}}}}; }

    nlohmann::json& json() { return json_; }

    // Appends `count` elements of `type` ("SCALAR", "VEC2"...) to the buffer as one buffer view
    // and accessor; returns the accessor's index.
    int AddAccessor(const void* data, size_t bytes, int component_type, const std::string& type,
                    size_t count) {
        while (bin_.size() % 4 != 0) bin_.push_back('\0');
        const size_t offset = bin_.size();
        bin_.append(static_cast<const char*>(data), bytes);
        json_["bufferViews"].push_back(
            {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
        json_["accessors"].push_back({{"bufferView", json_["bufferViews"].size() - 1},
                                      {"componentType", component_type},
                                      {"count", count},
                                      {"type", type}});
        return int(json_["accessors"].size()) - 1;
    }
    template <size_t N>
    int AddFloats(const std::vector<std::array<float, N>>& values) {
        static constexpr const char* kTypes[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
        return AddAccessor(values.data(), values.size() * N * 4, kFloat, kTypes[N], values.size());
    }
    int AddIndices(const std::vector<uint32_t>& indices) {
        return AddAccessor(indices.data(), indices.size() * 4, kUnsignedInt, "SCALAR",
                           indices.size());
    }

    // A mesh of one triangle primitive; returns the mesh index.
    int AddMesh(const std::string& name, nlohmann::json attributes, int indices, int material) {
        nlohmann::json primitive = {{"attributes", attributes}};
        if (indices >= 0) primitive["indices"] = indices;
        if (material >= 0) primitive["material"] = material;
        json_["meshes"].push_back({{"name", name}, {"primitives", {primitive}}});
        return int(json_["meshes"].size()) - 1;
    }
    int AddNode(nlohmann::json node) {
        json_["nodes"].push_back(std::move(node));
        return int(json_["nodes"].size()) - 1;
    }

    const std::string& bin() const { return bin_; }

    // The JSON with its buffer at `bin_uri` (write bin() there).
    std::string Gltf(const std::string& bin_uri) const { return WithBuffer(bin_uri); }
    std::string GltfEmbedded() const {
        return WithBuffer("data:application/octet-stream;base64," + absl::Base64Escape(bin_));
    }
    std::string Glb() const {
        nlohmann::json j = json_;
        j["buffers"] = {{{"byteLength", bin_.size()}}};
        std::string text = j.dump();
        while (text.size() % 4 != 0) text.push_back(' ');
        std::string bin = bin_;
        while (bin.size() % 4 != 0) bin.push_back('\0');
        std::string out = "glTF";
        Append32(out, 2);
        Append32(out, uint32_t(12 + 8 + text.size() + 8 + bin.size()));
        Append32(out, uint32_t(text.size()));
        out += "JSON" + text;
        Append32(out, uint32_t(bin.size()));
        out += std::string("BIN\0", 4) + bin;
        return out;
    }

  private:
    std::string WithBuffer(const std::string& uri) const {
        nlohmann::json j = json_;
        j["buffers"] = {{{"byteLength", bin_.size()}, {"uri", uri}}};
        return j.dump(1);
    }
    static void Append32(std::string& out, uint32_t v) {
        char bytes[4];
        std::memcpy(bytes, &v, 4);  // glTF is little-endian, as every machine we build for
        out.append(bytes, 4);
    }

    nlohmann::json json_;
    std::string bin_;
};

// The glTF the import tests share, and the JSON scene it equals: a parent node (translate,
// scale 2) over a rotated textured quad and a mirrored triangle, a camera (yfov 0.8, aspect 1.5)
// and a point light of 6830 cd (10 W/sr). The quad's material reads "tex.png" (2x2 RGBA, write
// TestTexturePng() there) through a clamping, nearest sampler. Where each vertex lands is worked
// out by hand in TexturedTestSceneJson.
inline std::vector<uint8_t> TestTexels() {
    return {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128};
}

inline GltfBuilder TexturedTestScene() {
    GltfBuilder b;
    nlohmann::json& j = b.json();
    const int quad_positions = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}, {{1, 1, 0}}, {{0, 1, 0}}});
    const int quad_normals = b.AddFloats<3>({{{0, 0, 1}}, {{0, 0, 1}}, {{0, 0, 1}}, {{0, 0, 1}}});
    const int quad_uvs = b.AddFloats<2>({{{0, 1}}, {{1, 1}}, {{1, 0}}, {{0, 0}}});
    const int quad_indices = b.AddIndices({0, 1, 2, 0, 2, 3});
    const int tri_positions = b.AddFloats<3>({{{0, 0, 0}}, {{1, 0, 0}}, {{0, 1, 0}}});
    j["images"] = {{{"uri", "tex.png"}, {"name", "checker"}}};
    j["samplers"] = {{{"magFilter", 9728}, {"wrapS", 33071}, {"wrapT", 33071}}};
    j["textures"] = {{{"source", 0}, {"sampler", 0}}};
    j["materials"] = {
        {{"name", "textured"},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {1, 1, 1, 1}},
           {"baseColorTexture", {{"index", 0}}},
           {"metallicFactor", 0},
           {"roughnessFactor", 0.5}}}},
        {{"name", "red"},
         {"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.1, 0.1, 1}}, {"metallicFactor", 0}}},
         {"doubleSided", true}}};
    const int quad = b.AddMesh(
        "quad", {{"POSITION", quad_positions}, {"NORMAL", quad_normals}, {"TEXCOORD_0", quad_uvs}},
        quad_indices, 0);
    const int tri = b.AddMesh("tri", {{"POSITION", tri_positions}}, -1, 1);
    const double s = std::sqrt(0.5);  // a quarter turn about +y
    const int quad_node = b.AddNode({{"name", "Quad"}, {"mesh", quad}, {"rotation", {0, s, 0, s}}});
    const int tri_node =
        b.AddNode({{"name", "Mirror"},
                   {"mesh", tri},
                   {"matrix", {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -3, 1}}});
    const int root = b.AddNode({{"name", "Root"},
                                {"translation", {1, 0, 0}},
                                {"scale", {2, 2, 2}},
                                {"children", {quad_node, tri_node}}});
    j["cameras"] = {{{"type", "perspective"},
                     {"name", "cam"},
                     {"perspective", {{"yfov", 0.8}, {"aspectRatio", 1.5}, {"znear", 0.1}}}}};
    const int camera = b.AddNode({{"name", "Front"}, {"camera", 0}, {"translation", {3, 1, 6}}});
    // Required, as Blender's exporter marks it whenever it writes lights.
    j["extensionsUsed"] = {"KHR_lights_punctual"};
    j["extensionsRequired"] = {"KHR_lights_punctual"};
    j["extensions"]["KHR_lights_punctual"]["lights"] = {
        {{"type", "point"}, {"color", {1, 0.5, 0.25}}, {"intensity", 6830}}};
    const int lamp = b.AddNode({{"name", "Lamp"},
                                {"translation", {3, 5, 0}},
                                {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    j["scenes"] = {{{"nodes", {root, camera, lamp}}}};
    j["scene"] = 0;
    return b;
}

// TexturedTestScene in lightfarm's JSON, with the same principled materials and texture. The
// quad, which needs texture coordinates and normals that a JSON quad cannot carry, comes from
// TexturedTestQuadObj through the glTF node's world transform: R_y(90) maps (x, y, z) to
// (z, y, -x), then scale 2 and translate (1, 0, 0). The triangle: mirrored in x and moved to
// z = -3, then the same; its winding is flipped to keep its front face.
inline std::string TexturedTestSceneJson() {
    const double fov = 0.8 * 180 / 3.14159265358979323846;
    // Ordered: lightfarm numbers materials in file order.
    nlohmann::ordered_json j = {
        {"camera",
         {{"position", {3, 1, 6}},
          {"look_at", {3, 1, 5}},
          {"up", {0, 1, 0}},
          {"fov_y_deg", fov},
          {"resolution", {1024, 683}}}},
        // glTF's defaults where the file says nothing: roughness 1, single-sided.
        {"materials",
         {{"textured",
           {{"type", "principled"},
            {"base_color", {1, 1, 1}},
            {"base_color_texture", {{"file", "tex.png"}, {"wrap", "clamp"}, {"filter", "nearest"}}},
            {"metallic", 0},
            {"roughness", 0.5},
            {"double_sided", false}}},
          {"red",
           {{"type", "principled"},
            {"base_color", {0.8, 0.1, 0.1}},
            {"metallic", 0},
            {"roughness", 1}}}}},
        {"shapes",
         {{{"type", "mesh"},
           {"file", "quad.obj"},
           {"material", "textured"},
           {"transform", {{"matrix", {0, 0, 2, 1, 0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 0, 1}}}}},
          {{"type", "triangle"},
           {"material", "red"},
           {"vertices", {{1, 0, -6}, {1, 2, -6}, {-1, 0, -6}}}}}},
        {"lights", {{{"type", "point"}, {"position", {3, 5, 0}}, {"intensity", {10, 5, 2.5}}}}}};
    return j.dump();
}

// TexturedTestScene's quad mesh as OBJ: OBJ's v runs up the image, so vt v is 1 - glTF's v.
inline std::string TexturedTestQuadObj() {
    return "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
           "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
           "vn 0 0 1\n"
           "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";
}

}  // namespace lf::testing
