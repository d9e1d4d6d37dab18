#include "lf/core/gltf_scene.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <set>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/photometry.h"
#include "lf/core/texture_io.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

// The extensions this importer reads. Anything else in extensionsUsed loses what it describes
// (a warning); in extensionsRequired it is an error.
const std::set<std::string>& SupportedExtensions() {
    static const std::set<std::string> kSupported = {
        "KHR_lights_punctual",   "KHR_materials_emissive_strength",
        "KHR_materials_ior",     "KHR_materials_transmission",
        "KHR_materials_volume",  "KHR_materials_specular",
        "KHR_texture_transform",
    };
    return kSupported;
}

// What a render loses when it ignores an extension, for the warning.
std::string WhatIsLost(const std::string& extension) {
    static const std::map<std::string, std::string> kLost = {
        {"KHR_materials_clearcoat", "the clear coat layer"},
        {"KHR_materials_sheen", "the sheen (cloth) lobe"},
        {"KHR_materials_iridescence", "thin-film iridescence"},
        {"KHR_materials_anisotropy", "anisotropic roughness; rendered isotropic"},
        {"KHR_materials_dispersion", "dispersion; one IOR for all wavelengths"},
        {"KHR_materials_unlit", "unlit shading; the material is lit as a PBR one"},
        {"KHR_materials_pbrSpecularGlossiness",
         "the specular-glossiness material; the "
         "metallic-roughness fallback is used"},
        {"KHR_materials_variants", "material variants; the default materials are used"},
        {"KHR_texture_basisu", "Basis Universal textures; the fallback images are used"},
        {"EXT_texture_webp", "WebP textures; the fallback images are used"},
        {"KHR_draco_mesh_compression",
         "Draco-compressed geometry; the uncompressed fallback is "
         "used"},
        {"EXT_meshopt_compression", "meshopt-compressed geometry; the fallback is used"},
        {"KHR_mesh_quantization", "nothing if the quantized attributes are floats"},
        {"EXT_mesh_gpu_instancing", "the instances; each mesh is rendered once"},
    };
    const auto found = kLost.find(extension);
    return found == kLost.end() ? "whatever it describes is ignored" : found->second;
}

std::string Quoted(const std::string& name) {
    return name.empty() ? std::string() : absl::StrCat(" \"", name, "\"");
}

// An error unwinds to AppendGltf as this, which adds the file name.
struct GltfError {
    std::string message;
};

[[noreturn]] void Fail(const std::string& where, const std::string& message) {
    throw GltfError{absl::StrCat(where, ": ", message)};
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
    if (!node.rotation.empty()) {
        double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2],
               w = node.rotation[3];
        const double norm = std::sqrt(x * x + y * y + z * z + w * w);
        if (!(norm > 0)) Fail(where, "rotation is the zero quaternion");
        x /= norm, y /= norm, z /= norm, w /= norm;
        m = {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), 0},
              {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), 0},
              {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), 0}}};
    }
    if (!node.scale.empty()) {
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) m[r][c] *= node.scale[c];
        }
    }
    if (!node.translation.empty()) {
        for (int r = 0; r < 3; ++r) m[r][3] = node.translation[r];
    }
    return local;
}

const char* ComponentTypeName(int type) {
    switch (type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return "BYTE";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return "UNSIGNED_BYTE";
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return "SHORT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return "UNSIGNED_SHORT";
        case TINYGLTF_COMPONENT_TYPE_INT:
            return "INT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            return "UNSIGNED_INT";
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return "FLOAT";
        case TINYGLTF_COMPONENT_TYPE_DOUBLE:
            return "DOUBLE";
        default:
            return "unknown";
    }
}

const char* ModeName(int mode) {
    switch (mode) {
        case TINYGLTF_MODE_POINTS:
            return "POINTS";
        case TINYGLTF_MODE_LINE:
            return "LINES";
        case TINYGLTF_MODE_LINE_LOOP:
            return "LINE_LOOP";
        case TINYGLTF_MODE_LINE_STRIP:
            return "LINE_STRIP";
        case TINYGLTF_MODE_TRIANGLE_STRIP:
            return "TRIANGLE_STRIP";
        case TINYGLTF_MODE_TRIANGLE_FAN:
            return "TRIANGLE_FAN";
        default:
            return "unknown";
    }
}

// One accessor's elements, checked to lie inside their buffer view and buffer.
struct AccessorData {
    const unsigned char* data = nullptr;
    size_t stride = 0, count = 0;
    int components = 0, component_type = 0, component_size = 0;
    bool normalized = false;
};

// Per-file state of one import.
class GltfImporter {
  public:
    GltfImporter(const tinygltf::Model& model, const std::string& name, const GltfImport& options,
                 Scene& scene, std::vector<GltfCamera>& cameras, std::vector<std::string>& warnings,
                 const std::map<int, absl::StatusOr<std::shared_ptr<const TextureImage>>>& images,
                 const std::map<std::string, absl::Status>& read_errors)
        : model_(model),
          name_(name),
          options_(options),
          scene_(scene),
          cameras_(cameras),
          warnings_(warnings),
          images_(images),
          read_errors_(read_errors) {}

    void Import() {
        CheckExtensions();
        if (!model_.animations.empty()) {
            Warn(absl::StrCat(model_.animations.size(),
                              " animations ignored: the rest pose is "
                              "rendered"));
        }
        if (!model_.skins.empty()) Warn("skins ignored: meshes are rendered unskinned");
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
        visited_.assign(model_.nodes.size(), false);
        const tinygltf::Scene& gltf_scene = model_.scenes[size_t(index)];
        for (size_t i = 0; i < gltf_scene.nodes.size(); ++i) {
            VisitNode(gltf_scene.nodes[i], options_.transform,
                      absl::StrCat("scenes[", index, "].nodes[", i, "]"));
        }
        if (range_ignored_) Warn("KHR_lights_punctual range ignored: lights fall off as 1/r^2");
    }

  private:
    void Warn(const std::string& message) { warnings_.push_back(message); }

    void CheckExtensions() {
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

    void VisitNode(int index, const Affine& parent, const std::string& ref) {
        if (index < 0 || index >= int(model_.nodes.size())) {
            Fail(ref, absl::StrCat(index, " is not a node index (the file has ",
                                   model_.nodes.size(), ")"));
        }
        const tinygltf::Node& node = model_.nodes[size_t(index)];
        const std::string where = absl::StrCat("nodes[", index, "]", Quoted(node.name));
        // glTF's hierarchy is a forest: a node reached twice is a cycle or a shared child.
        if (visited_[size_t(index)]) Fail(where, "reached twice: the node hierarchy is not a tree");
        visited_[size_t(index)] = true;
        const Affine world = LocalTransform(node, where).Then(parent);
        // Each node's numbers are finite, but a chain of large scales can overflow.
        if (!world.IsFinite()) Fail(where, "its world transform overflows double range");
        if (node.mesh >= 0) AddMesh(node.mesh, world, where);
        if (node.camera >= 0) AddCamera(node, world, where);
        if (const auto light = node.extensions.find("KHR_lights_punctual");
            light != node.extensions.end()) {
            AddLight(light->second.Get("light"), world, where);
        }
        for (size_t i = 0; i < node.children.size(); ++i) {
            VisitNode(node.children[i], world, absl::StrCat(where, ".children[", i, "]"));
        }
    }

    AccessorData Accessor(int index, const std::string& where) {
        if (index < 0 || index >= int(model_.accessors.size())) {
            Fail(where, absl::StrCat("accessor ", index, " does not exist (the file has ",
                                     model_.accessors.size(), ")"));
        }
        const tinygltf::Accessor& a = model_.accessors[size_t(index)];
        const std::string at = absl::StrCat(where, ": accessors[", index, "]", Quoted(a.name));
        if (a.sparse.isSparse) Fail(at, "sparse accessors are not supported");
        if (a.bufferView < 0 || a.bufferView >= int(model_.bufferViews.size())) {
            Fail(at, absl::StrCat("bufferView ", a.bufferView, " does not exist"));
        }
        const tinygltf::BufferView& view = model_.bufferViews[size_t(a.bufferView)];
        const std::string view_at = absl::StrCat(at, ": bufferViews[", a.bufferView, "]");
        if (view.buffer < 0 || view.buffer >= int(model_.buffers.size())) {
            Fail(view_at, absl::StrCat("buffer ", view.buffer, " does not exist"));
        }
        const tinygltf::Buffer& buffer = model_.buffers[size_t(view.buffer)];
        if (view.byteOffset > buffer.data.size() ||
            view.byteLength > buffer.data.size() - view.byteOffset) {
            Fail(view_at, absl::StrCat("bytes ", view.byteOffset, " to ",
                                       view.byteOffset + view.byteLength, " are beyond buffer ",
                                       view.buffer, " of ", buffer.data.size(), " bytes"));
        }
        AccessorData d;
        d.component_type = a.componentType;
        d.component_size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        d.components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (d.component_size <= 0 || d.components <= 0) {
            Fail(at, absl::StrCat("unknown componentType ", a.componentType, " or type ", a.type));
        }
        d.normalized = a.normalized;
        d.count = a.count;
        const size_t element = size_t(d.component_size) * size_t(d.components);
        d.stride = view.byteStride > 0 ? view.byteStride : element;
        if (d.stride < element) {
            Fail(view_at,
                 absl::StrCat("byteStride ", d.stride, " is below the element size ", element));
        }
        if (d.count > 0) {
            const size_t end = a.byteOffset + d.stride * (d.count - 1) + element;
            if (a.byteOffset > view.byteLength || d.count - 1 > (view.byteLength) / d.stride ||
                end > view.byteLength) {
                Fail(at, absl::StrCat(d.count, " elements from byte ", a.byteOffset,
                                      " run beyond bufferViews[", a.bufferView, "] of ",
                                      view.byteLength, " bytes"));
            }
        }
        d.data = buffer.data.data() + view.byteOffset + a.byteOffset;
        return d;
    }

    // An attribute's elements as floats, `components` per element: FLOAT, or the normalized
    // integer types glTF allows for texture coordinates and colours.
    std::vector<float> Floats(int index, int components, const std::string& where) {
        const AccessorData d = Accessor(index, where);
        if (d.components != components) {
            Fail(where, absl::StrCat("accessors[", index, "] has ", d.components,
                                     " components per element, expected ", components));
        }
        const bool is_float = d.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT;
        if (!is_float && !d.normalized) {
            Fail(where, absl::StrCat("accessors[", index, "] has componentType ",
                                     ComponentTypeName(d.component_type),
                                     " (not normalized); expected FLOAT"));
        }
        std::vector<float> out(d.count * size_t(components));
        for (size_t i = 0; i < d.count; ++i) {
            const unsigned char* e = d.data + i * d.stride;
            for (int c = 0; c < components; ++c) {
                float& v = out[i * size_t(components) + size_t(c)];
                const unsigned char* p = e + c * d.component_size;
                switch (d.component_type) {
                    case TINYGLTF_COMPONENT_TYPE_FLOAT:
                        std::memcpy(&v, p, 4);
                        break;
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                        v = float(*p) / 255.0f;
                        break;
                    case TINYGLTF_COMPONENT_TYPE_BYTE:
                        v = std::max(float(int8_t(*p)) / 127.0f, -1.0f);
                        break;
                    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                        uint16_t s;
                        std::memcpy(&s, p, 2);
                        v = float(s) / 65535.0f;
                        break;
                    }
                    case TINYGLTF_COMPONENT_TYPE_SHORT: {
                        int16_t s;
                        std::memcpy(&s, p, 2);
                        v = std::max(float(s) / 32767.0f, -1.0f);
                        break;
                    }
                    default:
                        Fail(where, absl::StrCat("accessors[", index, "] has componentType ",
                                                 ComponentTypeName(d.component_type),
                                                 ", which glTF does not allow here"));
                }
                if (!std::isfinite(v)) {
                    Fail(where, absl::StrCat("accessors[", index, "] element ", i, " component ", c,
                                             " is ", v));
                }
            }
        }
        return out;
    }

    std::vector<uint32_t> Indices(int index, size_t vertices, const std::string& where) {
        const AccessorData d = Accessor(index, where);
        if (d.components != 1) {
            Fail(where, absl::StrCat("accessors[", index, "] is not SCALAR"));
        }
        std::vector<uint32_t> out(d.count);
        for (size_t i = 0; i < d.count; ++i) {
            const unsigned char* p = d.data + i * d.stride;
            switch (d.component_type) {
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                    out[i] = *p;
                    break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                    uint16_t s;
                    std::memcpy(&s, p, 2);
                    out[i] = s;
                    break;
                }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
                    std::memcpy(&out[i], p, 4);
                    break;
                default:
                    Fail(where, absl::StrCat("accessors[", index, "] has componentType ",
                                             ComponentTypeName(d.component_type),
                                             "; indices are UNSIGNED_BYTE, _SHORT or _INT"));
            }
            if (out[i] >= vertices) {
                Fail(where, absl::StrCat("index ", i, " is ", out[i], " but the primitive has ",
                                         vertices, " vertices"));
            }
        }
        return out;
    }

    void AddMesh(int index, const Affine& world, const std::string& node_where) {
        if (index >= int(model_.meshes.size())) {
            Fail(node_where, absl::StrCat("mesh ", index, " does not exist"));
        }
        const tinygltf::Mesh& mesh = model_.meshes[size_t(index)];
        const Affine normal_matrix = world.NormalMatrix();
        const double det = world.Determinant();
        if (!(std::abs(det) > 0)) Fail(node_where, "its transform is singular (flattens the mesh)");
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            const tinygltf::Primitive& prim = mesh.primitives[p];
            const std::string where =
                absl::StrCat("meshes[", index, "]", Quoted(mesh.name), ".primitives[", p, "]");
            if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
                Fail(where, absl::StrCat("mode ", prim.mode, " (", ModeName(prim.mode),
                                         ") is not supported; only triangles (mode 4)"));
            }
            if (!prim.targets.empty()) Warn(absl::StrCat(where, ": morph targets ignored"));
            const auto attribute = [&](const char* key) {
                const auto found = prim.attributes.find(key);
                return found == prim.attributes.end() ? -1 : found->second;
            };
            const int position = attribute("POSITION");
            if (position < 0) Fail(where, "has no POSITION attribute");
            TriangleMesh out;
            out.name = mesh.name.empty() ? absl::StrCat(name_, "#", where)
                                         : absl::StrCat(mesh.name, "[", p, "]");
            out.material = Material(prim.material, where);
            const std::string at = absl::StrCat(where, ".attributes.");
            const std::vector<float> positions = Floats(position, 3, at + "POSITION");
            const size_t n = positions.size() / 3;
            out.positions.resize(n);
            for (size_t i = 0; i < n; ++i) {
                out.positions[i] = world.Apply(
                    Vec3d(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]));
            }
            if (const int normal = attribute("NORMAL"); normal >= 0) {
                const std::vector<float> normals = Floats(normal, 3, at + "NORMAL");
                if (normals.size() != positions.size()) Fail(at + "NORMAL", "count differs");
                out.normals.resize(n);
                for (size_t i = 0; i < n; ++i) {
                    const Vec3d v = normal_matrix.ApplyLinear(
                        Vec3d(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]));
                    const double length = Length(v);
                    if (!(length > 0)) {
                        Fail(at + "NORMAL", absl::StrCat("normal ", i, " is zero"));
                    }
                    out.normals[i] = Vec3(v / length);
                }
            }
            if (const int uv = attribute("TEXCOORD_0"); uv >= 0) {
                const std::vector<float> uvs = Floats(uv, 2, at + "TEXCOORD_0");
                if (uvs.size() / 2 != n) Fail(at + "TEXCOORD_0", "count differs from POSITION");
                out.uvs.resize(n);
                for (size_t i = 0; i < n; ++i) out.uvs[i] = {uvs[2 * i], uvs[2 * i + 1]};
            }
            if (const int tangent = attribute("TANGENT"); tangent >= 0) {
                const std::vector<float> t = Floats(tangent, 4, at + "TANGENT");
                if (t.size() / 4 != n) Fail(at + "TANGENT", "count differs from POSITION");
                out.tangents.resize(n);
                for (size_t i = 0; i < n; ++i) {
                    // Tangents lie in the surface and move with it; a mirror flips the
                    // bitangent's handedness.
                    const Vec3d v = world.ApplyLinear(Vec3d(t[4 * i], t[4 * i + 1], t[4 * i + 2]));
                    const double length = Length(v);
                    const Vec3 unit = length > 0 ? Vec3(v / length) : Vec3(1, 0, 0);
                    out.tangents[i] = {unit.x, unit.y, unit.z,
                                       (t[4 * i + 3] < 0 ? -1.0f : 1.0f) * (det < 0 ? -1 : 1)};
                }
            }
            std::vector<uint32_t> indices;
            if (prim.indices >= 0) {
                indices = Indices(prim.indices, n, at.substr(0, at.size() - 11) + "indices");
            } else {
                indices.resize(n);
                for (size_t i = 0; i < n; ++i) indices[i] = uint32_t(i);
            }
            if (indices.size() % 3 != 0) {
                Fail(where, absl::StrCat(indices.size(),
                                         " indices is not a whole number of "
                                         "triangles"));
            }
            out.triangles.resize(indices.size() / 3);
            for (size_t i = 0; i < out.triangles.size(); ++i) {
                // A mirroring transform would turn front faces into back faces.
                out.triangles[i] =
                    det < 0 ? std::array{indices[3 * i], indices[3 * i + 2], indices[3 * i + 1]}
                            : std::array{indices[3 * i], indices[3 * i + 1], indices[3 * i + 2]};
            }
            if (out.triangles.empty()) {
                Warn(absl::StrCat(where, ": no triangles, skipped"));
                continue;
            }
            scene_.meshes.push_back(std::move(out));
        }
    }

    void AddCamera(const tinygltf::Node& node, const Affine& world, const std::string& where) {
        if (node.camera >= int(model_.cameras.size())) {
            Fail(where, absl::StrCat("camera ", node.camera, " does not exist"));
        }
        const tinygltf::Camera& camera = model_.cameras[size_t(node.camera)];
        const std::string at = absl::StrCat("cameras[", node.camera, "]", Quoted(camera.name));
        if (camera.type != "perspective") {
            Fail(at, absl::StrCat("type \"", camera.type,
                                  "\" is not supported; lightfarm renders "
                                  "perspective cameras only"));
        }
        const tinygltf::PerspectiveCamera& p = camera.perspective;
        if (!(p.yfov > 0 && p.yfov < std::numbers::pi)) {
            Fail(at, absl::StrCat("yfov ", p.yfov, " must be in (0, pi) radians"));
        }
        GltfCamera out;
        out.name = node.name.empty() ? camera.name : node.name;
        CameraSpec& spec = out.spec;
        // The camera looks down its node's -Z with +Y up.
        spec.position = world.Apply(Vec3d(0, 0, 0));
        const Vec3d forward = world.ApplyLinear(Vec3d(0, 0, -1));
        spec.up = world.ApplyLinear(Vec3d(0, 1, 0));
        if (!(Length(Cross(forward, spec.up)) > 0)) Fail(where, "its transform is singular");
        spec.look_at = spec.position + Normalize(forward);
        spec.fov_y_deg = p.yfov * 180 / std::numbers::pi;
        const double aspect = p.aspectRatio > 0 ? p.aspectRatio : 1;
        if (!(aspect >= 1e-3 && aspect <= 1e3)) {
            Fail(at, absl::StrCat("aspectRatio ", p.aspectRatio, " is not within [0.001, 1000]"));
        }
        spec.width =
            aspect >= 1 ? kGltfLongerSide : std::max(1, int(std::lround(kGltfLongerSide * aspect)));
        spec.height =
            aspect >= 1 ? std::max(1, int(std::lround(kGltfLongerSide / aspect))) : kGltfLongerSide;
        cameras_.push_back(std::move(out));
    }

    void AddLight(const tinygltf::Value& light_index, const Affine& world,
                  const std::string& where) {
        const std::string at = where + ".extensions.KHR_lights_punctual.light";
        if (!light_index.IsNumber()) Fail(at, "missing or not a number");
        const int index = int(light_index.GetNumberAsDouble());
        if (index < 0 || index >= int(model_.lights.size())) {
            Fail(at, absl::StrCat(index, " is not a light index (the file has ",
                                  model_.lights.size(), ")"));
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
            Warn(absl::StrCat(where, ": ", light.type,
                              " light under a transform that flattens its axis, skipped"));
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

    // The scene material for glTF material `index` (-1: glTF's default material).
    int Material(int index, const std::string& where) {
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

    // glTF's default: white, fully metallic and rough, opaque, single-sided.
    lf::Material DefaultMaterial() const {
        lf::Material m;
        m.name = absl::StrCat(name_, "#default material");
        m.type = lf::Material::Type::kPrincipled;
        m.reflectance = Rgb(1.0f);
        m.metallic = 1;
        m.roughness = 1;
        m.double_sided = false;
        return m;
    }

    static double Number(const tinygltf::Value& object, const char* key, double fallback, double lo,
                         double hi, const std::string& where) {
        if (!object.Has(key)) return fallback;
        const tinygltf::Value& v = object.Get(key);
        if (!v.IsNumber()) Fail(where, absl::StrCat(key, " is not a number"));
        const double x = v.GetNumberAsDouble();
        if (!(x >= lo && x <= hi)) {
            Fail(where, absl::StrCat(key, " ", x, " is outside [", lo, ", ", hi, "]"));
        }
        return x;
    }

    static std::vector<double> Numbers(const tinygltf::Value& object, const char* key,
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

    static Rgb Color(const std::vector<double>& v, const std::string& where, const char* key) {
        for (double c : v) {
            if (!(c >= 0 && c <= 1))
                Fail(where, absl::StrCat(key, " holds ", c, ", not in [0, 1]"));
        }
        return Rgb(float(v[0]), float(v[1]), float(v[2]));
    }

    static const tinygltf::Value* Extension(const tinygltf::ExtensionMap& map, const char* key) {
        const auto found = map.find(key);
        return found == map.end() ? nullptr : &found->second;
    }

    lf::Material ConvertMaterial(int index) {
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
            Warn(absl::StrCat(where,
                              ": occlusionTexture ignored (a path tracer computes "
                              "occlusion itself)"));
        }
        m.emission_texture =
            Texture(g.emissiveTexture.index, g.emissiveTexture.texCoord,
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
            if (e->Has("transmissionTexture")) {
                Warn(at + ": transmissionTexture ignored; the factor applies everywhere");
            }
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
                Warn(at + ": thicknessTexture ignored; only whether thickness is 0 matters");
            }
        }
        if (const tinygltf::Value* e = Extension(g.extensions, "KHR_materials_specular")) {
            const std::string at = where + ".KHR_materials_specular";
            m.specular = float(Number(*e, "specularFactor", 1, 0, 1, at));
            const std::vector<double> tint = Numbers(*e, "specularColorFactor", {1, 1, 1}, at);
            if (tint != std::vector<double>{1, 1, 1} || e->Has("specularTexture") ||
                e->Has("specularColorTexture")) {
                Warn(at + ": specular colour and textures ignored; only specularFactor is used");
            }
        }
        m.double_sided = g.doubleSided;
        if (g.alphaMode == "MASK" || g.alphaMode == "BLEND") {
            m.alpha_mode = lf::Material::AlphaMode::kMask;
            m.alpha_cutoff = float(g.alphaCutoff);
            if (g.alphaMode == "BLEND") {
                Warn(where + ": alphaMode BLEND rendered as MASK with alphaCutoff 0.5");
                m.alpha_cutoff = 0.5f;
            }
            if (!(m.alpha_cutoff >= 0)) Fail(where, "alphaCutoff must be at least 0");
        } else if (g.alphaMode != "OPAQUE") {
            Fail(where, absl::StrCat("alphaMode \"", g.alphaMode,
                                     "\" is unknown; expected OPAQUE, MASK or BLEND"));
        }
        return m;
    }

    // The TextureRef of a material's texture slot; `srgb` for colour textures.
    TextureRef Texture(int index, int tex_coord, const tinygltf::ExtensionMap& extensions,
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
        if (tex_coord != 0) {
            Warn(absl::StrCat(where, ": uses TEXCOORD_", tex_coord,
                              "; lightfarm reads TEXCOORD_0 only and uses that"));
        }
        return ref;
    }

    static TextureRef::Wrap Wrap(int mode, const std::string& where) {
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

    // The Scene::textures index of glTF image `index`, decoded once however many textures use it.
    int Image(int index) {
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

    const tinygltf::Model& model_;
    const std::string& name_;
    const GltfImport& options_;
    Scene& scene_;
    std::vector<GltfCamera>& cameras_;
    std::vector<std::string>& warnings_;
    const std::map<int, absl::StatusOr<std::shared_ptr<const TextureImage>>>& images_;
    const std::map<std::string, absl::Status>& read_errors_;
    std::vector<bool> visited_;
    std::map<int, int> material_of_, texture_of_;
    bool range_ignored_ = false;
};

// What tinygltf's callbacks need: our reader, the glTF's folder, and where to put what they
// found. tinygltf calls them with the name it would open, joined to the base directory we give
// it (none): the URI as the glTF writes it, decoded.
struct LoadContext {
    const SceneFileReader* read_file;
    std::string base;  // the glTF's folder as the scene names it, "" beside the scene
    std::string name;  // the glTF, for image names
    std::map<std::string, absl::Status> read_errors;  // by URI
    std::map<int, absl::StatusOr<std::shared_ptr<const TextureImage>>> images;
};

bool AlwaysExists(const std::string&, void*) { return true; }
std::string AsIs(const std::string& path, void*) { return path; }

bool ReadThroughReader(std::vector<unsigned char>* out, std::string* err, const std::string& uri,
                       void* user) {
    auto* context = static_cast<LoadContext*>(user);
    const fs::path path(uri);
    const std::string name =
        path.is_absolute() ? uri : (fs::path(context->base) / path).lexically_normal().string();
    absl::StatusOr<std::string> bytes = (*context->read_file)(name);
    if (!bytes.ok()) {
        context->read_errors[uri] = bytes.status();
        *err = std::string(bytes.status().message());
        return false;
    }
    out->assign(bytes->begin(), bytes->end());
    return true;
}

bool NeverWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    *err = "writing is not supported";
    return false;
}

bool DecodeImage(tinygltf::Image* image, const int index, std::string*, std::string*, int, int,
                 const unsigned char* bytes, int size, void* user) {
    auto* context = static_cast<LoadContext*>(user);
    const std::string name = image->uri.empty() || image->uri.starts_with("data:")
                                 ? absl::StrCat(context->name, "#image", index)
                                 : image->uri;
    context->images.emplace(
        index,
        DecodeTexture(std::string(reinterpret_cast<const char*>(bytes), size_t(size)), name));
    return true;
}

}  // namespace

bool IsGltfName(const std::string& name) {
    const std::string ext = absl::AsciiStrToLower(fs::path(name).extension().string());
    return ext == ".gltf" || ext == ".glb";
}

absl::Status AppendGltf(const std::string& bytes, const std::string& name,
                        const SceneFileReader& read_file, const GltfImport& options, Scene& scene,
                        std::vector<GltfCamera>& cameras, std::vector<std::string>& warnings) {
    LoadContext context{&read_file, options.base_dir, name, {}, {}};
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks({&AlwaysExists, &AsIs, &ReadThroughReader, &NeverWrite, &context});
    loader.SetImageLoader(&DecodeImage, &context);
    tinygltf::Model model;
    std::string err, warn;
    const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) {
        return absl::InvalidArgumentError("larger than 4 GB");
    }
    if (binary) {
        // tinygltf says only "Invalid glTF binary" for the commonest .glb fault: a cut-off copy.
        uint32_t declared = 0;
        if (bytes.size() >= 12) std::memcpy(&declared, bytes.data() + 8, 4);
        if (bytes.size() < 12 || declared > bytes.size()) {
            return absl::InvalidArgumentError(absl::StrCat(
                "truncated glTF binary (.glb): ", bytes.size(), " bytes, its header ",
                bytes.size() < 12 ? "alone needs 12" : absl::StrCat("declares ", declared)));
        }
    }
    const bool ok =
        binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                             reinterpret_cast<const unsigned char*>(bytes.data()),
                                             unsigned(bytes.size()), "")
               : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(),
                                            unsigned(bytes.size()), "");
    if (!ok) {
        // A file the reader could not give is the cause the user can act on.
        for (const auto& [uri, status] : context.read_errors) {
            // Images that cannot be read only warn in tinygltf: this is a buffer.
            return absl::Status(status.code(),
                                absl::StrCat("buffer uri \"", uri, "\": ", status.message()));
        }
        absl::StripTrailingAsciiWhitespace(&err);
        return absl::InvalidArgumentError(
            absl::StrCat("not a valid glTF ", binary ? "binary (.glb)" : "file", ": ", err));
    }
    try {
        GltfImporter(model, name, options, scene, cameras, warnings, context.images,
                     context.read_errors)
            .Import();
    } catch (const GltfError& e) {
        return absl::InvalidArgumentError(e.message);
    }
    return absl::OkStatus();
}

absl::StatusOr<CameraSpec> ChooseGltfCamera(const std::vector<GltfCamera>& cameras,
                                            const std::string& name) {
    if (cameras.empty()) {
        return absl::NotFoundError(
            "no camera; add one to the glTF, or include the file from a JSON scene that gives "
            "a camera");
    }
    if (name.empty()) return cameras.front().spec;
    std::vector<std::string> names;
    for (const GltfCamera& camera : cameras) {
        if (camera.name == name) return camera.spec;
        names.push_back(absl::StrCat("\"", camera.name, "\""));
    }
    return absl::NotFoundError(absl::StrCat("no camera named \"", name, "\"; the cameras are ",
                                            absl::StrJoin(names, ", ")));
}

}  // namespace lf
