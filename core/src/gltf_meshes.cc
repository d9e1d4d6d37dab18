#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gltf_importer.h"

namespace lf::gltf_internal {
namespace {

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

}  // namespace

std::string_view GltfImporter::BufferView(int index, const std::string& where) {
    if (index < 0 || index >= int(model_.bufferViews.size())) {
        Fail(where, absl::StrCat("bufferView ", index, " does not exist"));
    }
    const tinygltf::BufferView& view = model_.bufferViews[size_t(index)];
    const std::string view_at = absl::StrCat(where, ": bufferViews[", index, "]");
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
    return {reinterpret_cast<const char*>(buffer.data.data()) + view.byteOffset, view.byteLength};
}

AccessorData GltfImporter::Declaration(int index, const std::string& where) {
    if (index < 0 || index >= int(model_.accessors.size())) {
        Fail(where, absl::StrCat("accessor ", index, " does not exist (the file has ",
                                 model_.accessors.size(), ")"));
    }
    const tinygltf::Accessor& a = model_.accessors[size_t(index)];
    const std::string at = absl::StrCat(where, ": accessors[", index, "]", Quoted(a.name));
    if (a.sparse.isSparse) Fail(at, "sparse accessors are not supported");
    AccessorData d;
    d.component_type = a.componentType;
    d.component_size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
    d.components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
    if (d.component_size <= 0 || d.components <= 0) {
        Fail(at, absl::StrCat("unknown componentType ", a.componentType, " or type ", a.type));
    }
    d.normalized = a.normalized;
    d.count = a.count;
    return d;
}

AccessorData GltfImporter::Accessor(int index, const std::string& where) {
    if (const auto decoded = decoded_.find(index); decoded != decoded_.end()) {
        return decoded->second.data;
    }
    AccessorData d = Declaration(index, where);
    const tinygltf::Accessor& a = model_.accessors[size_t(index)];
    const std::string at = absl::StrCat(where, ": accessors[", index, "]", Quoted(a.name));
    const std::string_view view = BufferView(a.bufferView, at);
    const size_t element = size_t(d.component_size) * size_t(d.components);
    const size_t byte_stride = model_.bufferViews[size_t(a.bufferView)].byteStride;
    d.stride = byte_stride > 0 ? byte_stride : element;
    if (d.stride < element) {
        Fail(absl::StrCat(at, ": bufferViews[", a.bufferView, "]"),
             absl::StrCat("byteStride ", d.stride, " is below the element size ", element));
    }
    if (d.count > 0) {
        const size_t end = a.byteOffset + d.stride * (d.count - 1) + element;
        if (a.byteOffset > view.size() || d.count - 1 > view.size() / d.stride ||
            end > view.size()) {
            Fail(at, absl::StrCat(d.count, " elements from byte ", a.byteOffset,
                                  " run beyond bufferViews[", a.bufferView, "] of ", view.size(),
                                  " bytes"));
        }
    }
    d.data = reinterpret_cast<const unsigned char*>(view.data()) + a.byteOffset;
    return d;
}

std::vector<float> GltfImporter::Floats(int index, int components, const std::string& where,
                                        bool any_value) {
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
            if (!any_value && !std::isfinite(v)) {
                Fail(where, absl::StrCat("accessors[", index, "] element ", i, " component ", c,
                                         " is ", v));
            }
        }
    }
    return out;
}

std::vector<uint32_t> GltfImporter::Indices(int index, size_t vertices, const std::string& where) {
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

void GltfImporter::AddMesh(int node, const Affine& world, const std::string& node_where) {
    const int index = model_.nodes[size_t(node)].mesh;
    // A node on a cycle of children is not in the animation's tree; the traversal refuses it.
    const bool in_tree = animating_ && node_of_[size_t(node)] >= 0;
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
        const auto attribute = [&](const char* key) {
            const auto found = prim.attributes.find(key);
            return found == prim.attributes.end() ? -1 : found->second;
        };
        const int position = attribute("POSITION");
        if (position < 0) Fail(where, "has no POSITION attribute");
        // A Draco primitive's accessors read what its bitstream decodes to.
        int indices_accessor = prim.indices;
        decoded_.clear();
        if (const tinygltf::Value* draco =
                Extension(prim.extensions, "KHR_draco_mesh_compression")) {
            indices_accessor = DecodeDraco(prim, *draco, where);
        }
        TriangleMesh out;
        out.name = mesh.name.empty() ? absl::StrCat(name_, "#", where)
                                     : absl::StrCat(mesh.name, "[", p, "]");
        out.material = Material(prim.material, where);
        const std::string at = absl::StrCat(where, ".attributes.");
        const std::vector<float> positions = Floats(position, 3, at + "POSITION");
        const size_t n = positions.size() / 3;
        out.positions.resize(n);
        for (size_t i = 0; i < n; ++i) {
            out.positions[i] =
                world.Apply(Vec3d(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]));
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
        const auto read_uvs = [&](const char* key, std::vector<Vec2>& out_uvs) {
            const int uv = attribute(key);
            if (uv < 0) return false;
            const std::vector<float> uvs = Floats(uv, 2, at + key);
            if (uvs.size() / 2 != n) Fail(at + key, "count differs from POSITION");
            out_uvs.resize(n);
            for (size_t i = 0; i < n; ++i) out_uvs[i] = {uvs[2 * i], uvs[2 * i + 1]};
            return true;
        };
        read_uvs("TEXCOORD_0", out.uvs);
        // The second set costs memory only where a texture reads it.
        if (scene_.materials[size_t(out.material)].ReadsUvs1() &&
            !read_uvs("TEXCOORD_1", out.uvs1)) {
            Tally("material reads TEXCOORD_1 the primitive lacks (uv (0, 0) used)", "primitive",
                  where);
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
        if (const int color = attribute("COLOR_0"); color >= 0) {
            // VEC3 or VEC4 of FLOAT or normalized UNSIGNED_BYTE/SHORT, linear.
            const int components = Accessor(color, at + "COLOR_0").components;
            if (components != 3 && components != 4) {
                Fail(at + "COLOR_0", absl::StrCat("accessors[", color, "] has ", components,
                                                  " components per element, expected 3 or 4"));
            }
            const std::vector<float> c = Floats(color, components, at + "COLOR_0");
            if (c.size() / size_t(components) != n) {
                Fail(at + "COLOR_0", "count differs from POSITION");
            }
            out.colors.resize(n);
            for (size_t i = 0; i < n; ++i) {
                const float* e = &c[i * size_t(components)];
                out.colors[i] = {std::clamp(e[0], 0.0f, 1.0f), std::clamp(e[1], 0.0f, 1.0f),
                                 std::clamp(e[2], 0.0f, 1.0f),
                                 components == 4 ? std::clamp(e[3], 0.0f, 1.0f) : 1.0f};
            }
        }
        std::vector<uint32_t> indices;
        if (indices_accessor >= 0) {
            indices = Indices(indices_accessor, n, at.substr(0, at.size() - 11) + "indices");
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
            Tally("no triangles, skipped", "primitive", where);
            continue;
        }
        scene_.meshes.push_back(std::move(out));
        if (in_tree) {
            AnimationStep(
                [&] { AnimateMesh(node, int(scene_.meshes.size()) - 1, int(p), node_where); });
        }
    }
}

}  // namespace lf::gltf_internal
