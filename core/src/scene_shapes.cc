#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "scene_parser.h"

namespace lf::scene_internal {
namespace {

// Twice a triangle's area below this fraction of its longest edge squared is within double
// rounding of zero: the triangle has no reliable normal and no area to sample.
constexpr double kDegenerateRatio = 1e-12;

// The medium on either side of a shape's surface (scene_media.cc).
constexpr std::array<std::string_view, 2> kMediaKeys = {"interior", "exterior"};

// False for NaN too, which a comparison of the largest component would let through.
bool WithinCoordinateRange(const Vec3d& p) {
    return std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate &&
           std::abs(p.z) <= kMaxCoordinate;
}

}  // namespace

std::array<double, 4> SceneParser::ParseRotation(const Node& rotate) {
    rotate.ExpectObject({"axis", "angle_deg"});
    const Node axis_node = rotate.Get("axis");
    const Vec3d axis = axis_node.Vector();
    if (LengthSquared(axis) == 0) axis_node.Fail("must not be zero");
    const Vec3d a = Normalize(axis);
    const double half = rotate.Get("angle_deg").Number() * std::numbers::pi / 360;
    const double s = std::sin(half);
    return {a.x * s, a.y * s, a.z * s, std::cos(half)};
}

Affine SceneParser::ParseTransform(const Node& n) {
    n.ExpectObject({"scale", "rotate", "translate", "matrix"});
    Affine transform;
    if (const std::optional<Node> matrix = n.Find("matrix")) {
        if (n.Has("scale") || n.Has("rotate") || n.Has("translate")) {
            n.Fail("give either matrix or scale/rotate/translate, not both");
        }
        const std::vector<Node> e = matrix->Elements(16);
        for (int i = 0; i < 12; ++i) transform.m[i / 4][i % 4] = e[i].Coordinate();
        for (int i = 12; i < 16; ++i) {
            if (e[i].Number() != (i == 15 ? 1 : 0)) {
                matrix->Fail("the last row must be [0, 0, 0, 1] (affine transforms only)");
            }
        }
    }
    if (const std::optional<Node> scale = n.Find("scale")) {
        const Vec3d s =
            scale->json().is_number() ? Vec3d(1, 1, 1) * scale->Coordinate() : scale->Vector();
        for (int a = 0; a < 3; ++a) transform.m[a][a] = s[a];
    }
    if (const std::optional<Node> rotate = n.Find("rotate")) {
        transform =
            transform.Then(Affine::FromTrs(Vec3d(0, 0, 0), ParseRotation(*rotate), Vec3d(1, 1, 1)));
    }
    if (const std::optional<Node> translate = n.Find("translate")) {
        const Vec3d t = translate->Vector();
        for (int a = 0; a < 3; ++a) transform.m[a][3] += t[a];
    }
    const double scale =
        Length(transform.Row(0)) * Length(transform.Row(1)) * Length(transform.Row(2));
    if (!(std::abs(transform.Determinant()) > kDegenerateRatio * scale)) {
        n.Fail("singular: it flattens the mesh");
    }
    return transform;
}

namespace {

// Drops triangles with repeated vertices or (near) zero area; returns how many.
int DropDegenerate(TriangleMesh& mesh) {
    const size_t before = mesh.triangles.size();
    std::erase_if(mesh.triangles, [&](const std::array<uint32_t, 3>& t) {
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
        const Vec3d& a = mesh.positions[t[0]];
        const Vec3d e0 = mesh.positions[t[1]] - a, e1 = mesh.positions[t[2]] - a, e2 = e1 - e0;
        const double longest = std::max({LengthSquared(e0), LengthSquared(e1), LengthSquared(e2)});
        return !(Length(Cross(e0, e1)) > kDegenerateRatio * longest);
    });
    return int(before - mesh.triangles.size());
}

// Moves a mesh's positions and normals by `transform`: normals by its inverse transpose.
void TransformMesh(const Affine& transform, TriangleMesh& mesh) {
    for (Vec3d& p : mesh.positions) p = transform.Apply(p);
    const Affine normal_matrix = transform.NormalMatrix();
    for (Vec3& n : mesh.normals) n = Vec3(Normalize(normal_matrix.ApplyLinear(Vec3d(n))));
    // A mirroring transform would turn front faces into back faces; keep them in front.
    if (transform.Determinant() < 0) {
        for (std::array<uint32_t, 3>& t : mesh.triangles) std::swap(t[1], t[2]);
    }
}

}  // namespace

void SceneParser::ParseShape(const Node& n, Scene& scene) {
    n.RequireObject();
    const Node type = n.Get("type");
    const std::string type_name = type.String();
    if (type_name == "gltf") return ParseGltfShape(n, scene);
    // A mesh file may give its own materials; every other shape names one.
    const std::optional<Node> material =
        type_name == "mesh" ? n.Find("material") : std::optional(n.Get("material"));
    int material_index = -1;
    if (material) {
        const auto found = material_index_.find(material->String());
        if (found == material_index_.end()) {
            material->Fail(absl::StrCat("unknown material \"", material->String(), "\""));
        }
        material_index = found->second;
    }
    const std::string name = n.Has("name") ? n.Get("name").String() : n.path();
    // Keyframed, the shape is a node of the animation, its geometry kept in its own space.
    const std::optional<Node> transform_node = n.Find("transform");
    const PlacedTransform placed =
        transform_node
            ? ParseAnyTransform(
                  *transform_node, type_name == "sphere" ? Scaling::kUniform : Scaling::kAny,
                  n.Has("name") ? absl::StrCat(n.path(), " \"", name, "\"") : n.path())
            : PlacedTransform{};
    const bool moves =
        std::any_of(animation_.channels.begin(), animation_.channels.end(),
                    [&](const AnimationChannel& c) { return c.node == placed.node; });

    if (type_name == "sphere") {
        n.WarnUnknownKeys({"type", "material", "name", "center", "radius", "transform"},
                          kMediaKeys);
        Sphere sphere{name, material_index, n.Get("center").Vector(), 0, ParseMediumInterface(n)};
        const Node radius = n.Get("radius");
        sphere.radius = radius.Number();
        if (!(sphere.radius > 0 && sphere.radius <= kMaxCoordinate)) {
            radius.Fail(absl::StrCat("must be in (0, 1e15], got ", sphere.radius));
        }
        if (placed.node >= 0) {
            animation_.spheres.push_back(
                {int(scene.spheres.size()), placed.node, sphere.center, sphere.radius, moves});
        }
        sphere.center = placed.rest.Apply(sphere.center);
        sphere.radius *= std::cbrt(std::abs(placed.rest.Determinant()));
        if (!WithinCoordinateRange(sphere.center) || !(sphere.radius <= kMaxCoordinate)) {
            n.Fail(absl::StrCat("after the transform the centre (", sphere.center.x, ", ",
                                sphere.center.y, ", ", sphere.center.z, ") or the radius ",
                                sphere.radius, " lies beyond 1e15"));
        }
        scene.spheres.push_back(sphere);
        return;
    }

    std::vector<TriangleMesh> meshes;
    if (type_name == "quad" || type_name == "triangle") {
        n.WarnUnknownKeys({"type", "material", "name", "vertices", "transform"}, kMediaKeys);
        const bool quad = type_name == "quad";
        TriangleMesh& mesh = meshes.emplace_back();
        for (const Node& v : n.Get("vertices").Elements(quad ? 4 : 3)) {
            mesh.positions.push_back(v.Vector());
        }
        mesh.triangles.push_back({0, 1, 2});
        if (quad) mesh.triangles.push_back({0, 2, 3});
        mesh.is_quad = quad;
        mesh.material = material_index;
    } else if (type_name == "mesh") {
        n.WarnUnknownKeys({"type", "material", "name", "file", "transform"}, kMediaKeys);
        meshes = LoadMeshShape(n, material_index, scene);
    } else {
        type.Fail(absl::StrCat("unknown shape type \"", type_name,
                               "\"; expected quad, triangle, mesh or sphere"));
    }

    const MediumInterface media = ParseMediumInterface(n);
    bool kept = false;
    for (TriangleMesh& mesh : meshes) {
        mesh.media = media;
        // One mesh per material of the file: each named for its material.
        mesh.name = meshes.size() == 1
                        ? name
                        : absl::StrCat(name, " (", scene.materials[mesh.material].name, ")");
        AnimatedMesh own;  // the geometry in the shape's space, for a keyframed transform
        if (placed.node >= 0) {
            own.positions = mesh.positions;
            for (const Vec3& normal : mesh.normals) own.normals.emplace_back(normal);
        }
        if (transform_node) TransformMesh(placed.rest, mesh);
        for (const Vec3d& p : mesh.positions) {
            if (!WithinCoordinateRange(p)) {
                n.Fail(absl::StrCat("a vertex of \"", mesh.name, "\" lies beyond ±1e15",
                                    transform_node ? " after the transform" : "", ": (", p.x, ", ",
                                    p.y, ", ", p.z, ")"));
            }
        }
        const int dropped = DropDegenerate(mesh);
        dropped_degenerate_ += dropped;
        if (mesh.triangles.empty()) continue;
        // Radiosity grids an is_quad mesh between its four corners, which no longer holds
        // once a triangle is gone.
        if (dropped > 0) mesh.is_quad = false;
        if (placed.node >= 0) {
            own.mesh = int(scene.meshes.size());
            own.node = placed.node;
            own.moves = moves;
            animation_.meshes.push_back(std::move(own));
        }
        scene.meshes.push_back(std::move(mesh));
        kept = true;
    }
    if (!kept) n.Fail("every triangle is degenerate (zero area or repeated vertices)");
}

std::vector<TriangleMesh> SceneParser::LoadMeshShape(const Node& n, int material_index,
                                                     Scene& scene) {
    const Node file = n.Get("file");
    const std::string name = file.String();
    if (name.empty()) file.Fail("empty file name");
    // Errors name the file as the scene does, never where a reader found it.
    const std::string where = absl::StrCat(file.path(), " \"", name, "\"");
    auto fail = [&](const absl::Status& status) {
        throw LoadError{absl::Status(status.code(), absl::StrCat(where, ": ", status.message()))};
    };
    // Keyed by the name as written ("./m.obj" is "m.obj"), never by where the reader found
    // it: the same keys, so the same content hash, on the farm as on the user's disk.
    const bool own_materials = material_index < 0;
    const std::pair key(std::filesystem::path(name).lexically_normal().string(), own_materials);
    auto cached = mesh_cache_.find(key);
    if (cached == mesh_cache_.end()) {
        absl::StatusOr<std::string> bytes = read_file_(name);
        if (!bytes.ok()) fail(bytes.status());
        hash_.Update(*bytes);
        // MTL files count in the content hash like the meshes that name them.
        const SceneFileReader read_and_hash = [&](const std::string& mtl) {
            absl::StatusOr<std::string> text = read_file_(mtl);
            if (text.ok()) hash_.Update(*text);
            return text;
        };
        absl::StatusOr<MeshFile> loaded;
        if (own_materials) {
            loaded = ParseMeshWithMaterials(*bytes, name, read_and_hash);
        } else if (absl::StatusOr<TriangleMesh> mesh = ParseMesh(*bytes, name); mesh.ok()) {
            loaded.emplace().meshes.push_back(*std::move(mesh));
        } else {
            loaded = mesh.status();
        }
        if (!loaded.ok()) {
            throw LoadError{
                absl::Status(loaded.status().code(),
                             absl::StrCat(file.path(), ": ", loaded.status().message()))};
        }
        for (const std::string& warning : loaded->warnings) {
            warnings_.push_back(absl::StrCat(where, ": ", warning));
        }
        cached = mesh_cache_.emplace(key, AddFileMaterials(*std::move(loaded), where, scene)).first;
    }
    if (!cached->second.unassigned_where.empty()) {
        n.Fail(absl::StrCat("missing required key \"material\": the faces of ",
                            cached->second.unassigned_where,
                            " have no material from the file (only an OBJ file's mtllib "
                            "and usemtl give one)"));
    }
    std::vector<TriangleMesh> meshes = cached->second.meshes;
    if (!own_materials) meshes[0].material = material_index;
    return meshes;
}

CachedMeshFile SceneParser::AddFileMaterials(MeshFile file, const std::string& where,
                                             Scene& scene) {
    std::vector<int> image_of;
    for (const MeshFile::Texture& texture : file.textures) {
        image_of.push_back(TextureIndex(texture.name, absl::StrCat(where, ": ", texture.where)));
    }
    const int first = int(scene.materials.size());
    for (Material& m : file.materials) {
        for (TextureRef* ref : {&m.base_color_texture, &m.metallic_roughness_texture,
                                &m.normal_texture, &m.emission_texture, &m.transmission_texture}) {
            if (ref->valid()) ref->image = image_of[size_t(ref->image)];
        }
        scene.materials.push_back(std::move(m));
    }
    for (TriangleMesh& mesh : file.meshes) {
        if (mesh.material >= 0) mesh.material += first;
    }
    return {std::move(file.meshes), file.unassigned_where.empty() ? "" : file.unassigned_where[0]};
}

void SceneParser::ImportGltf(const std::string& bytes, const std::string& name,
                             const std::string& base_dir, const Affine& transform, Scene& scene,
                             const std::function<void(const absl::Status&)>& fail, bool included) {
    const SceneFileReader hashing_reader =
        [&](const std::string& file) -> absl::StatusOr<std::string> {
        absl::StatusOr<std::string> read = read_file_(file);
        if (read.ok()) hash_.Update(*read);
        return read;
    };
    const size_t first_mesh = scene.meshes.size();
    std::vector<std::string> warnings;
    const absl::Status status = AppendGltf(bytes, name, hashing_reader,
                                           {base_dir, transform, &animation_, &animation_error_},
                                           scene, gltf_cameras_, warnings);
    for (const std::string& w : warnings) {
        warnings_.push_back(included ? absl::StrCat(name, ": ", w) : w);
    }
    if (!status.ok()) fail(status);
    for (size_t i = first_mesh; i < scene.meshes.size(); ++i) {
        dropped_degenerate_ += DropDegenerate(scene.meshes[i]);
        for (const Vec3d& p : scene.meshes[i].positions) {
            if (!WithinCoordinateRange(p)) {
                fail(absl::InvalidArgumentError(
                    absl::StrCat("mesh \"", scene.meshes[i].name, "\" has a vertex beyond ±1e15")));
            }
        }
    }
    // Meshes left without triangles go; the animation's mesh indices follow the rest.
    std::vector<int> index_after(scene.meshes.size(), -1);
    for (int i = 0, kept = 0; i < int(scene.meshes.size()); ++i) {
        if (!scene.meshes[size_t(i)].triangles.empty()) index_after[size_t(i)] = kept++;
    }
    std::erase_if(scene.meshes, [](const TriangleMesh& m) { return m.triangles.empty(); });
    std::erase_if(animation_.meshes,
                  [&](const AnimatedMesh& m) { return index_after[size_t(m.mesh)] < 0; });
    for (AnimatedMesh& m : animation_.meshes) m.mesh = index_after[size_t(m.mesh)];
}

void SceneParser::ParseGltfShape(const Node& n, Scene& scene) {
    n.WarnUnknownKeys({"type", "file", "transform"}, kMediaKeys);
    const Node file = n.Get("file");
    const std::string name = file.String();
    if (name.empty()) file.Fail("empty file name");
    const std::optional<Node> transform = n.Find("transform");
    if (transform && transform->Has("keyframes")) {
        transform->Fail("a glTF's transform is fixed; animate its nodes in the glTF itself");
    }
    auto fail = [&](const absl::Status& status) {
        throw LoadError{absl::Status(
            status.code(), absl::StrCat(file.path(), " \"", name, "\": ", status.message()))};
    };
    absl::StatusOr<std::string> bytes = read_file_(name);
    if (!bytes.ok()) fail(bytes.status());
    hash_.Update(*bytes);
    const size_t first_mesh = scene.meshes.size();
    ImportGltf(*bytes, name, std::filesystem::path(name).parent_path().string(),
               transform ? ParseTransform(*transform) : Affine(), scene, fail, true);
    // Every mesh of the file sits between the same media.
    const MediumInterface media = ParseMediumInterface(n);
    for (size_t i = first_mesh; i < scene.meshes.size(); ++i) scene.meshes[i].media = media;
}

}  // namespace lf::scene_internal
