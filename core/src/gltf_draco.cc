// KHR_draco_mesh_compression: a primitive whose indices and attributes are one Draco bitstream.
#include <draco/compression/config/compression_shared.h>
#include <draco/compression/decode.h>
#include <draco/compression/point_cloud/point_cloud_decoder.h>
#include <draco/core/varint_decoding.h>
#include <draco/mesh/mesh.h>

#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "gltf_importer.h"

namespace lf::gltf_internal {
namespace {

constexpr const char* kDraco = "KHR_draco_mesh_compression";

uint32_t Read32(const std::string& bytes, size_t at) {
    uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
}

void Append32(std::string& out, uint32_t v) {
    char bytes[4];
    std::memcpy(bytes, &v, 4);
    out.append(bytes, 4);
}

// Moves each Draco primitive's "indices" into its extension object. False when nothing changed.
bool MoveIndices(nlohmann::json& gltf) {
    bool changed = false;
    const auto meshes = gltf.find("meshes");
    if (meshes == gltf.end() || !meshes->is_array()) return false;
    for (nlohmann::json& mesh : *meshes) {
        if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) {
            continue;
        }
        for (nlohmann::json& primitive : mesh["primitives"]) {
            if (!primitive.is_object() || !primitive.contains("extensions") ||
                !primitive["extensions"].is_object()) {
                continue;
            }
            nlohmann::json& draco = primitive["extensions"][kDraco];
            if (!draco.is_object()) continue;
            if (primitive.contains("indices")) {
                draco["indices"] = primitive["indices"];
                primitive.erase("indices");
            } else {
                draco.erase("indices");
            }
            changed = true;
        }
    }
    return changed;
}

// The faces (and, for sequential connectivity, points) a Draco mesh bitstream declares, read
// from its connectivity header before anything is decoded or allocated. Only for bitstream
// version 2.2 (what current encoders write) without metadata; nullopt otherwise, and the counts
// are compared once decoded.
struct DeclaredCounts {
    uint32_t faces = 0;
    std::optional<uint32_t> points;  // edgebreaker meshes find theirs while decoding
};
std::optional<DeclaredCounts> Declared(const unsigned char* data, size_t size) {
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(data), size);
    draco::DracoHeader header;
    if (!draco::PointCloudDecoder::DecodeHeader(&buffer, &header).ok()) return std::nullopt;
    if (header.version_major != 2 || header.version_minor != 2 ||
        header.encoder_type != draco::TRIANGULAR_MESH || (header.flags & METADATA_FLAG_MASK)) {
        return std::nullopt;
    }
    buffer.set_bitstream_version(DRACO_BITSTREAM_VERSION(2, 2));
    DeclaredCounts out;
    if (header.encoder_method == draco::MESH_SEQUENTIAL_ENCODING) {
        uint32_t points = 0;
        if (!draco::DecodeVarint(&out.faces, &buffer) || !draco::DecodeVarint(&points, &buffer)) {
            return std::nullopt;
        }
        out.points = points;
        return out;
    }
    if (header.encoder_method == draco::MESH_EDGEBREAKER_ENCODING) {
        uint8_t traversal;
        uint32_t vertices = 0;
        if (!buffer.Decode(&traversal) || !draco::DecodeVarint(&vertices, &buffer) ||
            !draco::DecodeVarint(&out.faces, &buffer)) {
            return std::nullopt;
        }
        return out;
    }
    return std::nullopt;
}

// One attribute's values for its points, as `accessor`'s componentType lays them out.
template <typename T>
std::vector<unsigned char> Convert(const draco::PointAttribute& attribute, size_t points,
                                   int components, const std::string& where) {
    std::vector<unsigned char> out(points * size_t(components) * sizeof(T));
    T* values = reinterpret_cast<T*>(out.data());
    for (size_t i = 0; i < points; ++i) {
        const draco::AttributeValueIndex v = attribute.mapped_index(draco::PointIndex(uint32_t(i)));
        if (!attribute.ConvertValue<T>(v, int8_t(components), values + i * size_t(components))) {
            Fail(where, absl::StrCat("value ", i, " does not fit the accessor's componentType"));
        }
    }
    return out;
}

}  // namespace

std::string PrepareDraco(const std::string& bytes, bool binary) {
    if (bytes.find(kDraco) == std::string::npos) return bytes;
    // A .glb: header (12 bytes), then the JSON chunk's length and type, then the JSON.
    size_t json_size = bytes.size();
    uint32_t declared = uint32_t(bytes.size());
    if (binary) {
        if (bytes.size() < 20 || bytes.compare(16, 4, "JSON") != 0) return bytes;
        json_size = Read32(bytes, 12);
        declared = Read32(bytes, 8);
        if (declared > bytes.size() || json_size > declared - 20) return bytes;
    }
    nlohmann::json gltf =
        nlohmann::json::parse(std::string_view(bytes).substr(binary ? 20 : 0, json_size), nullptr,
                              /*allow_exceptions=*/false);
    // Malformed JSON is tinygltf's to report.
    if (gltf.is_discarded() || !gltf.is_object() || !MoveIndices(gltf)) return bytes;
    std::string json = gltf.dump();
    if (!binary) return json;
    while (json.size() % 4 != 0) json.push_back(' ');
    const std::string chunks = bytes.substr(20 + json_size, declared - 20 - json_size);
    std::string out = bytes.substr(0, 8);
    Append32(out, uint32_t(20 + json.size() + chunks.size()));
    Append32(out, uint32_t(json.size()));
    out += "JSON" + json + chunks;
    return out;
}

int GltfImporter::DecodeDraco(const tinygltf::Primitive& primitive, const tinygltf::Value& draco,
                              const std::string& where) {
    const std::string at = absl::StrCat(where, ".extensions.", kDraco);
    decoded_.clear();
    if (!draco.IsObject()) Fail(at, "is not an object");
    const tinygltf::Value& indices_value = draco.Get("indices");
    if (!indices_value.IsInt()) {
        Fail(where, "has no indices accessor; a Draco primitive is an indexed triangle mesh");
    }
    const int indices = indices_value.GetNumberAsInt();
    const AccessorData indices_accessor = Declaration(indices, where + ".indices");
    const tinygltf::Value& view_value = draco.Get("bufferView");
    if (!view_value.IsInt()) Fail(at, "has no bufferView");
    const std::string_view stream =
        BufferView(view_value.GetNumberAsInt(), absl::StrCat(at, ".bufferView"));
    const tinygltf::Value& ids = draco.Get("attributes");
    if (!ids.IsObject()) Fail(at, "has no attributes object");

    // Bounded before anything is decoded: the accessors' counts, which the bitstream's must
    // equal, and, where its header says, the bitstream's own.
    const auto position = primitive.attributes.find("POSITION");
    if (position == primitive.attributes.end()) Fail(where, "has no POSITION attribute");
    const size_t points = Declaration(position->second, where + ".attributes.POSITION").count;
    if (points > kMaxDracoPoints || indices_accessor.count / 3 > kMaxDracoFaces) {
        Fail(at, absl::StrCat(points, " points and ", indices_accessor.count / 3,
                              " faces is more than lightfarm decodes (", kMaxDracoPoints,
                              " points, ", kMaxDracoFaces, " faces)"));
    }
    const auto* data = reinterpret_cast<const unsigned char*>(stream.data());
    if (const std::optional<DeclaredCounts> declared = Declared(data, stream.size())) {
        if (uint64_t(declared->faces) * 3 != indices_accessor.count ||
            (declared->points && *declared->points != points)) {
            Fail(at,
                 absl::StrCat(
                     "the bitstream declares ", declared->faces, " faces",
                     declared->points ? absl::StrCat(" and ", *declared->points, " points") : "",
                     "; the accessors say ", indices_accessor.count / 3, " faces and ", points,
                     " points"));
        }
    }

    draco::DecoderBuffer buffer;
    buffer.Init(stream.data(), stream.size());
    const auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
    if (!type.ok() || type.value() != draco::TRIANGULAR_MESH) {
        Fail(at, absl::StrCat("bufferViews[", view_value.GetNumberAsInt(),
                              "] is not a Draco triangle mesh",
                              type.ok() ? "" : absl::StrCat(": ", type.status().error_msg())));
    }
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok()) {
        Fail(at, absl::StrCat("the Draco bitstream in bufferViews[", view_value.GetNumberAsInt(),
                              "] cannot be decoded: ", decoded.status().error_msg()));
    }
    const draco::Mesh& mesh = *decoded.value();
    if (size_t(mesh.num_faces()) * 3 != indices_accessor.count || mesh.num_points() != points) {
        Fail(at, absl::StrCat("decoded ", mesh.num_faces(), " faces and ", mesh.num_points(),
                              " points; the accessors say ", indices_accessor.count / 3,
                              " faces and ", points, " points"));
    }

    Decoded& corners = decoded_[indices];
    corners.bytes.resize(indices_accessor.count * 4);
    auto* out = reinterpret_cast<uint32_t*>(corners.bytes.data());
    for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f) {
        for (int k = 0; k < 3; ++k) *out++ = mesh.face(f)[k].value();
    }
    corners.data = {corners.bytes.data(),
                    4,
                    indices_accessor.count,
                    1,
                    TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                    4,
                    false};

    for (const std::string& semantic : ids.Keys()) {
        const std::string attribute_at = absl::StrCat(at, ".attributes.", semantic);
        const tinygltf::Value& id = ids.Get(semantic);
        const auto accessor = primitive.attributes.find(semantic);
        if (accessor == primitive.attributes.end()) {
            Fail(attribute_at, "is not among the primitive's attributes");
        }
        if (!id.IsInt()) Fail(attribute_at, "is not an attribute id");
        const draco::PointAttribute* attribute =
            mesh.GetAttributeByUniqueId(uint32_t(id.GetNumberAsInt()));
        if (attribute == nullptr) {
            Fail(attribute_at,
                 absl::StrCat("attribute id ", id.GetNumberAsInt(), " is not in the bitstream"));
        }
        AccessorData d = Declaration(accessor->second, attribute_at);
        if (d.count != points) {
            Fail(attribute_at, absl::StrCat("accessors[", accessor->second, "] has ", d.count,
                                            " elements; the bitstream has ", points, " points"));
        }
        if (attribute->num_components() != d.components) {
            Fail(attribute_at,
                 absl::StrCat("attribute id ", id.GetNumberAsInt(), " has ",
                              int(attribute->num_components()), " components; accessors[",
                              accessor->second, "] has ", d.components));
        }
        Decoded& values = decoded_[accessor->second];
        switch (d.component_type) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT:
                values.bytes = Convert<float>(*attribute, points, d.components, attribute_at);
                break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                values.bytes = Convert<uint8_t>(*attribute, points, d.components, attribute_at);
                break;
            case TINYGLTF_COMPONENT_TYPE_BYTE:
                values.bytes = Convert<int8_t>(*attribute, points, d.components, attribute_at);
                break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
                values.bytes = Convert<uint16_t>(*attribute, points, d.components, attribute_at);
                break;
            case TINYGLTF_COMPONENT_TYPE_SHORT:
                values.bytes = Convert<int16_t>(*attribute, points, d.components, attribute_at);
                break;
            default:
                Fail(attribute_at, absl::StrCat("accessors[", accessor->second,
                                                "] has a componentType glTF does not allow here"));
        }
        d.data = values.bytes.data();
        d.stride = size_t(d.components) * size_t(d.component_size);
        values.data = d;
    }
    return indices;
}

}  // namespace lf::gltf_internal
