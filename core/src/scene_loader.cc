#include "lf/core/scene_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/affine.h"
#include "lf/core/blackbody.h"
#include "lf/core/file_util.h"
#include "lf/core/gltf_scene.h"
#include "lf/core/log.h"
#include "lf/core/mesh_io.h"
#include "lf/core/mesh_tangents.h"
#include "lf/core/photometry.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/texture.h"
#include "lf/core/texture_io.h"

namespace lf {
namespace {

// Keeps the materials object in file order, which is the order of Scene::materials.
using Json = nlohmann::ordered_json;

// Beyond this a coordinate is a unit mistake or garbage, and the float kernels would have no
// precision left for the geometry's detail.
constexpr double kMaxCoordinate = 1e15;
constexpr int kMaxResolution = 65536;
constexpr int64_t kMaxPixels = int64_t(1) << 28;
// False for NaN too, which a comparison of the largest component would let through.
bool WithinCoordinateRange(const Vec3d& p) {
    return std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate &&
           std::abs(p.z) <= kMaxCoordinate;
}

// Twice a triangle's area below this fraction of its longest edge squared is within double
// rounding of zero: the triangle has no reliable normal and no area to sample.
constexpr double kDegenerateRatio = 1e-12;
constexpr float kMaxFloat = std::numeric_limits<float>::max();
// Emitted radiance (W m^-2 sr^-1) and point-light intensity (W/sr): 500 times the sun's
// radiance. Far above it, a light's power overflows float in the light sampler and samples
// reach the film's clamp (1e15, film.cc), both silently wrong.
constexpr float kMaxRadiance = 1e10f;

// Keys any material may have besides its type's: its emission (docs/scene-format.md, Emission).
constexpr std::array<std::string_view, 6> kEmissionKeys = {
    "emission", "luminance_nits", "power_lm", "color", "temperature_k", "two_sided"};

// Validation runs many levels deep; an error unwinds to ParseScene as this exception, which adds
// the source name, so every check stays one line.
struct LoadError {
    absl::Status status;
};

// FNV-1a, 128-bit (Fowler, Noll, Vo): not cryptographic, but content_hash only has to tell
// changed inputs apart, and this needs no library.
class Fnv1a128 {
  public:
    void Update(std::string_view bytes) {
        constexpr unsigned __int128 kPrime = (unsigned __int128)1 << 88 | 0x13b;
        for (const char c : bytes) {
            state_ ^= static_cast<unsigned char>(c);
            state_ *= kPrime;
        }
    }
    std::string Hex() const {
        static constexpr char kDigits[] = "0123456789abcdef";
        std::string hex(32, '0');
        for (int i = 0; i < 32; ++i) hex[31 - i] = kDigits[int(state_ >> (4 * i)) & 15];
        return hex;
    }

  private:
    unsigned __int128 state_ = (unsigned __int128)0x6c62272e07bb0142 << 64 | 0x62b821756295c58d;
};

// nlohmann reports a number too large for a double without its position; as a SAX parser this
// sees the byte offset of every error, so each one can name a line and column.
class LocatingDomParser : public nlohmann::detail::json_sax_dom_parser<Json> {
  public:
    explicit LocatingDomParser(Json& result) : json_sax_dom_parser(result, false) {}

    bool parse_error(std::size_t byte, const std::string&, const nlohmann::detail::exception& e) {
        error_byte = byte;
        error = e.what();
        return false;
    }

    std::size_t error_byte = 0;
    std::string error;
};

absl::Status ParseJson(const std::string& text, const std::string& source, Json& root) {
    LocatingDomParser parser(root);
    if (Json::sax_parse(text, &parser)) return absl::OkStatus();
    // The offset counts the characters read, so the offending one is just before it.
    const size_t at = std::min(text.size(), parser.error_byte > 0 ? parser.error_byte - 1 : 0);
    const size_t line = 1 + std::count(text.begin(), text.begin() + at, '\n');
    const size_t newline = at == 0 ? std::string::npos : text.rfind('\n', at - 1);
    const size_t column = at + 1 - (newline == std::string::npos ? 0 : newline + 1);
    // Drop nlohmann's "[json.exception.parse_error.101] parse error at line 2, column 9: ".
    std::string message = parser.error.substr(parser.error.find(']') + 2);
    if (message.starts_with("parse error")) message = message.substr(message.find(": ") + 2);
    return absl::InvalidArgumentError(
        absl::StrCat(source, ":", line, ":", column, ": JSON syntax error: ", message));
}

std::string Describe(const Json& json) {
    if (json.is_string()) return absl::StrCat("string \"", json.get<std::string>(), "\"");
    if (json.is_number()) return absl::StrCat("number ", json.get<double>());
    return json.type_name();
}

// A JSON value with its path from the root (`shapes[2].vertices[1]`), for messages.
class Node {
  public:
    Node(const Json& json, std::string path, std::vector<std::string>* warnings)
        : json_(json), path_(std::move(path)), warnings_(warnings) {}

    const Json& json() const { return json_; }
    const std::string& path() const { return path_; }

    [[noreturn]] void Fail(const std::string& message) const {
        throw LoadError{absl::InvalidArgumentError(
            path_.empty() ? std::string(message) : absl::StrCat(path_, ": ", message))};
    }

    void RequireObject() const {
        if (!json_.is_object()) Fail(absl::StrCat("expected an object, got ", Describe(json_)));
    }

    // Unknown keys are most likely typos, but they do not make the scene unusable.
    // `also`: keys every object of a kind shares (a material's emission keys).
    void WarnUnknownKeys(std::initializer_list<std::string_view> known,
                         std::span<const std::string_view> also = {}) const {
        for (const auto& [key, value] : json_.items()) {
            if (std::find(known.begin(), known.end(), key) == known.end() &&
                std::find(also.begin(), also.end(), key) == also.end()) {
                warnings_->push_back(absl::StrCat(Child(key), ": unknown key, ignored"));
            }
        }
    }

    void ExpectObject(std::initializer_list<std::string_view> known) const {
        RequireObject();
        WarnUnknownKeys(known);
    }

    bool Has(const std::string& key) const { return json_.contains(key); }

    std::optional<Node> Find(const std::string& key) const {
        if (!json_.contains(key)) return std::nullopt;
        return Node(json_.at(key), Child(key), warnings_);
    }

    Node Get(const std::string& key) const {
        if (!json_.contains(key)) Fail(absl::StrCat("missing required key \"", key, "\""));
        return Node(json_.at(key), Child(key), warnings_);
    }

    // The elements of an array; `count`, when given, is required.
    std::vector<Node> Elements(std::optional<size_t> count = std::nullopt) const {
        if (!json_.is_array()) Fail(absl::StrCat("expected an array, got ", Describe(json_)));
        if (count && json_.size() != *count) {
            Fail(absl::StrCat("expected ", *count, " elements, got ", json_.size()));
        }
        std::vector<Node> elements;
        for (size_t i = 0; i < json_.size(); ++i) {
            elements.emplace_back(json_[i], absl::StrCat(path_, "[", i, "]"), warnings_);
        }
        return elements;
    }

    std::string String() const {
        if (!json_.is_string()) Fail(absl::StrCat("expected a string, got ", Describe(json_)));
        return json_.get<std::string>();
    }

    // One of `choices`, by its spelling in the file; anything else is an error naming `what`
    // and listing the spellings ("expected a, b or c").
    template <typename T>
    T OneOf(std::string_view what,
            std::initializer_list<std::pair<std::string_view, T>> choices) const {
        const std::string name = String();
        std::string expected;
        size_t i = 0;
        for (const auto& [spelling, value] : choices) {
            if (spelling == name) return value;
            expected += absl::StrCat(i == 0                    ? ""
                                     : i + 1 == choices.size() ? " or "
                                                               : ", ",
                                     std::string(spelling));
            ++i;
        }
        Fail(absl::StrCat("unknown ", std::string(what), " \"", name, "\"; expected ", expected));
    }

    bool Bool() const {
        if (!json_.is_boolean())
            Fail(absl::StrCat("expected true or false, got ", Describe(json_)));
        return json_.get<bool>();
    }

    double Number() const {
        if (!json_.is_number()) Fail(absl::StrCat("expected a number, got ", Describe(json_)));
        const double value = json_.get<double>();
        if (!std::isfinite(value)) Fail("not a finite number");
        return value;
    }

    double NumberIn(double lo, double hi, const std::string& range) const {
        const double value = Number();
        if (!(value >= lo && value <= hi)) Fail(absl::StrCat("must be ", range, ", got ", value));
        return value;
    }

    // A number in (0, kMaxFloat]: the kernels keep material parameters in float.
    float PositiveFloat() const {
        const double value = Number();
        if (!(value > 0 && value <= kMaxFloat)) {
            Fail(absl::StrCat("must be a positive float, got ", value));
        }
        return float(value);
    }

    int Integer(int lo, int hi) const {
        const double value = NumberIn(lo, hi, absl::StrCat("an integer in [", lo, ", ", hi, "]"));
        if (value != std::floor(value)) Fail(absl::StrCat("must be an integer, got ", value));
        return int(value);
    }

    double Coordinate() const { return NumberIn(-kMaxCoordinate, kMaxCoordinate, "within ±1e15"); }

    // [x, y, z], each a Coordinate().
    Vec3d Vector() const {
        const std::vector<Node> e = Elements(3);
        return {e[0].Coordinate(), e[1].Coordinate(), e[2].Coordinate()};
    }

    // [r, g, b], each in [0, max].
    Rgb Color(float max) const {
        const std::vector<Node> e = Elements(3);
        const std::string range = max == 1           ? "in [0, 1]"
                                  : max == kMaxFloat ? "≥ 0 and below 3.4e38 (float range)"
                                                     : absl::StrCat("≥ 0 and at most ", max);
        return {float(e[0].NumberIn(0, max, range)), float(e[1].NumberIn(0, max, range)),
                float(e[2].NumberIn(0, max, range))};
    }

  private:
    std::string Child(const std::string& key) const {
        return path_.empty() ? std::string(key) : absl::StrCat(path_, ".", key);
    }

    const Json& json_;
    std::string path_;
    std::vector<std::string>* warnings_;
};

Affine ParseTransform(const Node& n) {
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
        rotate->ExpectObject({"axis", "angle_deg"});
        const Node axis_node = rotate->Get("axis");
        const Vec3d axis = axis_node.Vector();
        if (LengthSquared(axis) == 0) axis_node.Fail("must not be zero");
        const Vec3d a = Normalize(axis);
        const double angle = rotate->Get("angle_deg").Number() * std::numbers::pi / 180;
        const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
        Affine rotation;  // Rodrigues: counter-clockwise looking down the axis at the origin
        rotation.m = {{{t * a.x * a.x + c, t * a.x * a.y - s * a.z, t * a.x * a.z + s * a.y, 0},
                       {t * a.x * a.y + s * a.z, t * a.y * a.y + c, t * a.y * a.z - s * a.x, 0},
                       {t * a.x * a.z - s * a.y, t * a.y * a.z + s * a.x, t * a.z * a.z + c, 0}}};
        transform = transform.Then(rotation);
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

// A mesh file's meshes as a scene uses them.
struct CachedMeshFile {
    std::vector<TriangleMesh> meshes;
    std::string unassigned_where;  // where faces without a material are, when they need one
};

class SceneParser {
  public:
    SceneParser(const SceneFileReader& read_file, const SceneOptions& options)
        : read_file_(read_file), options_(options) {}

    Scene Parse(const Json& json, const std::string& text) {
        hash_.Update(text);
        const Node root(json, "", &warnings_);
        root.ExpectObject({"version", "camera", "materials", "shapes", "lights"});
        if (const std::optional<Node> version = root.Find("version")) {
            if (version->Number() != 1) version->Fail("unsupported; this build reads version 1");
        }
        Scene scene;
        textures_ = &scene.textures;
        // Optional when an included glTF may bring a camera (ResolveCamera).
        const std::optional<Node> camera =
            IncludesGltf(root) ? root.Find("camera") : std::optional(root.Get("camera"));
        if (camera) scene.camera = ParseCamera(*camera);

        const Node materials = root.Get("materials");
        materials.RequireObject();
        for (const auto& [name, value] : materials.json().items()) {
            material_index_[name] = int(scene.materials.size());
            scene.materials.push_back(
                ParseMaterial(name, Node(value, absl::StrCat("materials.", name), &warnings_)));
        }

        const std::vector<Node> shapes = root.Get("shapes").Elements();
        if (shapes.empty()) root.Get("shapes").Fail("no shapes; a scene needs at least one");
        for (const Node& shape : shapes) ParseShape(shape, scene);
        ResolveEmittedPower(scene);

        if (const std::optional<Node> lights = root.Find("lights")) {
            for (const Node& light : lights->Elements()) ParseLight(light, scene);
        }

        ResolveCamera(root, camera.has_value(), scene);
        return Finish(scene);
    }

    // A glTF file as the whole scene: its camera, or the one options_.camera names.
    Scene ParseGltf(const std::string& bytes, const std::string& source) {
        hash_.Update(bytes);
        Scene scene;
        // The reader resolves names beside the scene file already.
        ImportGltf(bytes, std::filesystem::path(source).filename().string(), "", Affine(), scene,
                   [](const absl::Status& s) { throw LoadError{s}; });
        absl::StatusOr<CameraSpec> camera = ChooseGltfCamera(gltf_cameras_, options_.camera);
        if (!camera.ok()) throw LoadError{camera.status()};
        scene.camera = *camera;
        return Finish(scene);
    }

    const std::vector<std::string>& warnings() const { return warnings_; }

  private:
    Scene Finish(Scene& scene) {
        if (options_.width > 0 || options_.height > 0) {
            if (!(options_.width >= 1 && options_.width <= kMaxResolution && options_.height >= 1 &&
                  options_.height <= kMaxResolution &&
                  int64_t(options_.width) * options_.height <= kMaxPixels)) {
                throw LoadError{absl::InvalidArgumentError(absl::StrCat(
                    "resolution ", options_.width, "x", options_.height, ": expected 1 to ",
                    kMaxResolution, " per side and at most 2^28 pixels"))};
            }
            scene.camera.width = options_.width;
            scene.camera.height = options_.height;
        }
        if (options_.filter) {
            if (const absl::Status status = CheckPixelFilter(*options_.filter); !status.ok()) {
                throw LoadError{absl::InvalidArgumentError(
                    absl::StrCat("--filter ", PixelFilterTypeName(options_.filter->type), ": ",
                                 status.message()))};
            }
            scene.camera.filter = *options_.filter;
        }
        if (!scene.HasLights()) {
            warnings_.push_back("no emissive shape and no light: the image will be black");
        }
        scene.dropped_degenerate = dropped_degenerate_;
        scene.content_hash = hash_.Hex();
        return std::move(scene);
    }

    static bool IncludesGltf(const Node& root) {
        const Json& shapes = root.json().contains("shapes") ? root.json()["shapes"] : Json();
        return shapes.is_array() && std::any_of(shapes.begin(), shapes.end(), [](const Json& s) {
                   return s.is_object() && s.value("type", Json()) == "gltf";
               });
    }

    // The JSON's camera unless --camera names a glTF one; the first glTF camera without either.
    void ResolveCamera(const Node& root, bool json_camera, Scene& scene) {
        if (json_camera && options_.camera.empty()) return;
        if (!json_camera && gltf_cameras_.empty()) {
            root.Fail("missing required key \"camera\" (no included glTF has a camera)");
        }
        if (gltf_cameras_.empty()) {
            root.Fail(absl::StrCat("--camera \"", options_.camera,
                                   "\": the scene has no named cameras (only glTF cameras have "
                                   "names)"));
        }
        absl::StatusOr<CameraSpec> camera = ChooseGltfCamera(gltf_cameras_, options_.camera);
        if (!camera.ok()) {
            throw LoadError{absl::Status(camera.status().code(),
                                         absl::StrCat("--camera: ", camera.status().message()))};
        }
        scene.camera = *camera;
    }

    // Appends glTF `name` (read as `bytes`) to `scene`, every file it reads hashed, its meshes
    // checked as a JSON mesh's are. `fail` throws the error with the caller's context.
    void ImportGltf(const std::string& bytes, const std::string& name, const std::string& base_dir,
                    const Affine& transform, Scene& scene,
                    const std::function<void(const absl::Status&)>& fail) {
        const SceneFileReader hashing_reader =
            [&](const std::string& file) -> absl::StatusOr<std::string> {
            absl::StatusOr<std::string> read = read_file_(file);
            if (read.ok()) hash_.Update(*read);
            return read;
        };
        const size_t first_mesh = scene.meshes.size();
        std::vector<std::string> warnings;
        const absl::Status status = AppendGltf(bytes, name, hashing_reader, {base_dir, transform},
                                               scene, gltf_cameras_, warnings);
        for (const std::string& w : warnings) warnings_.push_back(absl::StrCat(name, ": ", w));
        if (!status.ok()) fail(status);
        for (size_t i = first_mesh; i < scene.meshes.size(); ++i) {
            dropped_degenerate_ += DropDegenerate(scene.meshes[i]);
            for (const Vec3d& p : scene.meshes[i].positions) {
                if (!WithinCoordinateRange(p)) {
                    fail(absl::InvalidArgumentError(absl::StrCat("mesh \"", scene.meshes[i].name,
                                                                 "\" has a vertex beyond ±1e15")));
                }
            }
        }
        std::erase_if(scene.meshes, [](const TriangleMesh& m) { return m.triangles.empty(); });
    }

    // {"type": "gltf", "file": ..., "transform": ...}: a glTF file's meshes, materials, lights
    // and cameras in a JSON scene.
    void ParseGltfShape(const Node& n, Scene& scene) {
        n.WarnUnknownKeys({"type", "file", "transform"});
        const Node file = n.Get("file");
        const std::string name = file.String();
        if (name.empty()) file.Fail("empty file name");
        auto fail = [&](const absl::Status& status) {
            throw LoadError{absl::Status(
                status.code(), absl::StrCat(file.path(), " \"", name, "\": ", status.message()))};
        };
        absl::StatusOr<std::string> bytes = read_file_(name);
        if (!bytes.ok()) fail(bytes.status());
        hash_.Update(*bytes);
        const std::optional<Node> transform = n.Find("transform");
        ImportGltf(*bytes, name, std::filesystem::path(name).parent_path().string(),
                   transform ? ParseTransform(*transform) : Affine(), scene, fail);
    }

    CameraSpec ParseCamera(const Node& n) {
        n.ExpectObject({"position", "look_at", "up", "fov_y_deg", "resolution", "aperture_radius",
                        "focus_distance", "filter"});
        CameraSpec camera;
        camera.position = n.Get("position").Vector();
        const Node look_at = n.Get("look_at");
        camera.look_at = look_at.Vector();
        const Vec3d view = camera.look_at - camera.position;
        if (LengthSquared(view) == 0) look_at.Fail("equals camera.position");
        if (const std::optional<Node> up = n.Find("up")) {
            camera.up = up->Vector();
            if (LengthSquared(camera.up) == 0 ||
                Length(Cross(Normalize(view), Normalize(camera.up))) < 1e-6) {
                up->Fail("is zero or parallel to the view direction");
            }
        } else if (Length(Cross(Normalize(view), camera.up)) < 1e-6) {
            n.Fail("the default up [0, 1, 0] is parallel to the view direction; give `up`");
        }
        const Node fov = n.Get("fov_y_deg");
        camera.fov_y_deg = fov.Number();
        if (!(camera.fov_y_deg > 0 && camera.fov_y_deg < 180)) {
            fov.Fail(absl::StrCat("must be in (0, 180) degrees, got ", camera.fov_y_deg));
        }
        const Node resolution = n.Get("resolution");
        const std::vector<Node> size = resolution.Elements(2);
        camera.width = size[0].Integer(1, kMaxResolution);
        camera.height = size[1].Integer(1, kMaxResolution);
        if (int64_t(camera.width) * camera.height > kMaxPixels) {
            resolution.Fail(
                absl::StrCat(camera.width, " x ", camera.height, " is more than 2^28 pixels"));
        }
        if (const std::optional<Node> aperture = n.Find("aperture_radius")) {
            camera.aperture_radius = aperture->NumberIn(0, kMaxCoordinate, "≥ 0 (scene units)");
        }
        // By default the camera focuses on what it looks at.
        camera.focus_distance = Length(view);
        if (const std::optional<Node> focus = n.Find("focus_distance")) {
            camera.focus_distance = focus->NumberIn(0, kMaxCoordinate, "above 0 (scene units)");
            if (camera.focus_distance == 0) focus->Fail("must be above 0 (scene units)");
        }
        if (const std::optional<Node> filter = n.Find("filter"))
            camera.filter = ParseFilter(*filter);
        return camera;
    }

    // {"type": "box" | "gaussian" | "blackman-harris", "width": pixels}. Without a width: 1 for
    // the box, 3 for the others (pbrt-v4's default Gaussian, sigma 0.5 pixel, radius 1.5).
    static PixelFilter ParseFilter(const Node& n) {
        n.ExpectObject({"type", "width"});
        const Node type = n.Get("type");
        const std::optional<PixelFilter::Type> found = PixelFilterTypeFromName(type.String());
        if (!found) {
            type.Fail(absl::StrCat("unknown filter type \"", type.String(),
                                   "\"; expected box, gaussian or blackman-harris"));
        }
        PixelFilter filter{*found, *found == PixelFilter::Type::kBox ? 1.0 : 3.0};
        const std::optional<Node> width = n.Find("width");
        if (width) filter.width = width->Number();
        if (const absl::Status status = CheckPixelFilter(filter); !status.ok()) {
            (width ? *width : n).Fail(std::string(status.message()));
        }
        return filter;
    }

    Material ParseMaterial(const std::string& name, const Node& n) {
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
        } else {
            type.Fail(
                absl::StrCat("unknown material type \"", type_name,
                             "\"; expected lambert, mirror, glossy, dielectric or principled"));
        }
        ParseEmission(n, m);
        return m;
    }

    // `emission` (W m^-2 sr^-1), `luminance_nits` or `power_lm` with their colour, and
    // `two_sided`. power_lm waits for every shape (ResolveEmittedPower): it is spread over them.
    void ParseEmission(const Node& n, Material& m) {
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

    // Lambert's albedo and principled's base colour: `base_color` or its older name
    // `reflectance`, times `base_color_texture` when given. Without a texture the colour is
    // required; with one it defaults to white, the texture alone.
    void ParseBaseColor(const Node& n, Material& m) {
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

    // glTF 2.0's metallic-roughness material; defaults as Blender's Principled BSDF.
    void ParsePrincipled(const Node& n, Material& m) {
        n.WarnUnknownKeys({"type",
                           "base_color",
                           "reflectance",
                           "base_color_texture",
                           "metallic",
                           "roughness",
                           "metallic_roughness_texture",
                           "specular",
                           "ior",
                           "transmission",
                           "thickness",
                           "attenuation_color",
                           "attenuation_distance",
                           "normal_texture",
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
        m.transmission = fraction("transmission", 0);
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
        if (const std::optional<Node> scale = n.Find("normal_scale")) {
            m.normal_scale = float(scale->NumberIn(-kMaxFloat, kMaxFloat, "a finite float"));
        }
        if (const std::optional<Node> texture = n.Find("emission_texture")) {
            m.emission_texture = ParseTexture(*texture, true);
        }
        if (const std::optional<Node> mode = n.Find("alpha_mode")) {
            m.alpha_mode = mode->OneOf<Material::AlphaMode>(
                "alpha mode",
                {{"opaque", Material::AlphaMode::kOpaque}, {"mask", Material::AlphaMode::kMask}});
        }
        if (const std::optional<Node> sided = n.Find("double_sided"))
            m.double_sided = sided->Bool();
    }

    // A texture: a file name, or {"file", "wrap", "filter", "transform"}.
    TextureRef ParseTexture(const Node& n, bool srgb) {
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

    // The index in Scene::textures of image file `name`, read and decoded once per scene.
    // `where` (a JSON path, an MTL file's line) starts messages.
    int TextureIndex(const std::string& name, const std::string& where) {
        const std::string key = std::filesystem::path(name).lexically_normal().string();
        if (const auto found = texture_index_.find(key); found != texture_index_.end()) {
            return found->second;
        }
        textures_->push_back(DecodeFile(name, where));
        return texture_index_[key] = int(textures_->size() - 1);
    }

    // Image file `name`, read through the scene's reader (so `submit` uploads it) and hashed.
    std::shared_ptr<const TextureImage> DecodeFile(const std::string& name,
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

    void ParseShape(const Node& n, Scene& scene) {
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

        if (type_name == "sphere") {
            n.WarnUnknownKeys({"type", "material", "name", "center", "radius"});
            Sphere sphere{name, material_index, n.Get("center").Vector(), 0};
            const Node radius = n.Get("radius");
            sphere.radius = radius.Number();
            if (!(sphere.radius > 0 && sphere.radius <= kMaxCoordinate)) {
                radius.Fail(absl::StrCat("must be in (0, 1e15], got ", sphere.radius));
            }
            scene.spheres.push_back(sphere);
            return;
        }

        std::vector<TriangleMesh> meshes;
        if (type_name == "quad" || type_name == "triangle") {
            n.WarnUnknownKeys({"type", "material", "name", "vertices"});
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
            n.WarnUnknownKeys({"type", "material", "name", "file", "transform"});
            meshes = LoadMeshShape(n, material_index, scene);
        } else {
            type.Fail(absl::StrCat("unknown shape type \"", type_name,
                                   "\"; expected quad, triangle, mesh or sphere"));
        }

        bool kept = false;
        for (TriangleMesh& mesh : meshes) {
            // One mesh per material of the file: each named for its material.
            mesh.name = meshes.size() == 1
                            ? name
                            : absl::StrCat(name, " (", scene.materials[mesh.material].name, ")");
            const int dropped = DropDegenerate(mesh);
            dropped_degenerate_ += dropped;
            if (mesh.triangles.empty()) continue;
            // Radiosity grids an is_quad mesh between its four corners, which no longer holds
            // once a triangle is gone.
            if (dropped > 0) mesh.is_quad = false;
            scene.meshes.push_back(std::move(mesh));
            kept = true;
        }
        if (!kept) n.Fail("every triangle is degenerate (zero area or repeated vertices)");
    }

    // A mesh file's meshes: with `material_index` (>= 0) one mesh of that material, otherwise
    // one per material of the file (an OBJ's MTL files), those materials added to the scene.
    std::vector<TriangleMesh> LoadMeshShape(const Node& n, int material_index, Scene& scene) {
        const Node file = n.Get("file");
        const std::string name = file.String();
        if (name.empty()) file.Fail("empty file name");
        // Errors name the file as the scene does, never where a reader found it.
        const std::string where = absl::StrCat(file.path(), " \"", name, "\"");
        auto fail = [&](const absl::Status& status) {
            throw LoadError{
                absl::Status(status.code(), absl::StrCat(where, ": ", status.message()))};
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
            cached =
                mesh_cache_.emplace(key, AddFileMaterials(*std::move(loaded), where, scene)).first;
        }
        if (!cached->second.unassigned_where.empty()) {
            n.Fail(absl::StrCat("missing required key \"material\": the faces of ",
                                cached->second.unassigned_where,
                                " have no material from the file (only an OBJ file's mtllib "
                                "and usemtl give one)"));
        }
        std::vector<TriangleMesh> meshes = cached->second.meshes;
        if (!own_materials) meshes[0].material = material_index;

        const std::optional<Node> transform_node = n.Find("transform");
        const Affine transform = transform_node ? ParseTransform(*transform_node) : Affine();
        for (TriangleMesh& mesh : meshes) {
            if (transform_node) TransformMesh(transform, mesh);
            for (const Vec3d& p : mesh.positions) {
                if (!WithinCoordinateRange(p)) {
                    n.Fail(absl::StrCat("a vertex of ", name, " lies beyond ±1e15",
                                        n.Has("transform") ? " after the transform" : "", ": (",
                                        p.x, ", ", p.y, ", ", p.z, ")"));
                }
            }
        }
        return meshes;
    }

    // A mesh file's materials join the scene's, their textures its textures; the meshes'
    // material indices become the scene's.
    CachedMeshFile AddFileMaterials(MeshFile file, const std::string& where, Scene& scene) {
        std::vector<int> image_of;
        for (const MeshFile::Texture& texture : file.textures) {
            image_of.push_back(
                TextureIndex(texture.name, absl::StrCat(where, ": ", texture.where)));
        }
        const int first = int(scene.materials.size());
        for (Material& m : file.materials) {
            for (TextureRef* ref : {&m.base_color_texture, &m.metallic_roughness_texture,
                                    &m.normal_texture, &m.emission_texture}) {
                if (ref->valid()) ref->image = image_of[size_t(ref->image)];
            }
            scene.materials.push_back(std::move(m));
        }
        for (TriangleMesh& mesh : file.meshes) {
            if (mesh.material >= 0) mesh.material += first;
        }
        return {std::move(file.meshes),
                file.unassigned_where.empty() ? "" : file.unassigned_where[0]};
    }

    void ParseLight(const Node& n, Scene& scene) {
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
                n, *FindStrength(
                       n, {{"irradiance", "W/m^2", false}, {"illuminance_lux", "lx", true}}, true));
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

    SpotLight ParseSpot(const Node& n) {
        // inner_cone_deg and outer_cone_deg: the names before issue 13, still read.
        n.WarnUnknownKeys({"type", "position", "direction", "intensity", "power", "intensity_cd",
                           "power_lm", "color", "temperature_k", "inner_angle_deg",
                           "outer_angle_deg", "inner_cone_deg", "outer_cone_deg"});
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
        light.intensity =
            RadiantIntensity(n, 2 * std::numbers::pi * (1 - (cos_inner + cos_outer) / 2));
        return light;
    }

    EnvironmentLight ParseEnvironment(const Node& n) {
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
        light.map = DecodeFile(name, file->path());
        if (!light.map->hdr) {
            file->Fail(absl::StrCat("\"", name,
                                    "\" is an 8- or 16-bit image of display values, not radiance; "
                                    "give a Radiance HDR or OpenEXR map"));
        }
        const Rgb tint = LightColor(n, photometric);
        if (!photometric) {
            light.radiance = tint * float(scale);
        } else {
            const double mean = MeanLuminance(*light.map, tint);
            if (!(mean > 0)) {
                file->Fail(absl::StrCat("\"", name, "\" is black: luminance_nits cannot scale it"));
            }
            const double nits = strength->value.NumberIn(0, kLumensPerWatt * kMaxRadiance,
                                                         "≥ 0 and at most 6.8e12");
            light.radiance = tint * float(nits / (kLumensPerWatt * mean));
        }
        return checked();
    }

    // The luminance (Rec.709 Y) of a lat-long map times `tint`, averaged over the sphere of
    // directions: each texel weighs its solid angle, (cos theta_top - cos theta_bottom) of its
    // row times 2 pi / width, its radiance taken as constant over it.
    static double MeanLuminance(const TextureImage& map, const Rgb& tint) {
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

    // A unit direction from a non-zero vector.
    static Vec3d Direction(const Node& n) {
        const Vec3d v = n.Vector();
        if (LengthSquared(v) == 0) n.Fail("must not be zero");
        return Normalize(v);
    }

    // A light's strength: a key, its unit (for messages), whether it is photometric, and what
    // divides it into the stored quantity (a power over the emission's solid angle).
    struct StrengthKey {
        const char* name;
        const char* unit;
        bool photometric;
        double divisor = 1;
    };
    struct Strength {
        StrengthKey key;
        Node value;
    };

    // The one strength of `keys` that light `n` gives; none (when not `required`) or several
    // are errors.
    static std::optional<Strength> FindStrength(const Node& n,
                                                std::initializer_list<StrengthKey> keys,
                                                bool required) {
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

    // A strength as the radiometric quantity the scene model keeps (W/sr, W/m^2 or
    // W m^-2 sr^-1 per channel). Radiometric: [r, g, b], or a number times the light's colour.
    // Photometric: a number times the colour at luminance 1, at 683 lm/W.
    static Rgb StrengthValue(const Node& light, const Strength& strength) {
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

    // A light's intensity in W/sr: given, or its power over `solid_angle` (the light's emission
    // integrated over directions, relative to its peak), radiometric or photometric.
    static Rgb RadiantIntensity(const Node& n, double solid_angle) {
        return StrengthValue(n, *FindStrength(n,
                                              {{"intensity", "W/sr", false},
                                               {"power", "W", false, solid_angle},
                                               {"intensity_cd", "cd", true},
                                               {"power_lm", "lm", true, solid_angle}},
                                              true));
    }

    // A light's or emitter's colour: `color` or `temperature_k` (a black body, luminance 1),
    // white by default. With a photometric strength `color` is scaled to luminance 1, so the
    // strength alone sets the luminous quantity.
    static Rgb LightColor(const Node& light, bool photometric) {
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

    // Each power_lm material's luminance: its power over the area of every shape using it, out
    // of one face (pi L A) or both (2 pi L A).
    void ResolveEmittedPower(Scene& scene) {
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

    const SceneFileReader& read_file_;
    const SceneOptions& options_;
    std::vector<GltfCamera> gltf_cameras_;
    std::vector<std::string> warnings_;
    std::map<std::string, int> material_index_;
    // power_lm emitters, resolved once every shape is loaded.
    struct PendingPower {
        int material;
        Node value;
    };
    std::vector<PendingPower> pending_power_;
    std::string environment_path_;  // the first environment light's JSON path
    // By name and whether the file's own materials were read.
    std::map<std::pair<std::string, bool>, CachedMeshFile> mesh_cache_;
    std::map<std::string, int> texture_index_;  // by file name, into *textures_
    std::vector<std::shared_ptr<const TextureImage>>* textures_ = nullptr;  // the scene's
    Fnv1a128 hash_;
    int dropped_degenerate_ = 0;
};

}  // namespace

SceneFileReader ReadBeside(const std::string& base_dir) {
    return [base_dir](const std::string& name) {
        std::filesystem::path path(name);
        if (path.is_relative()) path = std::filesystem::path(base_dir) / path;
        return ReadFile(path.lexically_normal().string());
    };
}

absl::StatusOr<Scene> LoadScene(const std::string& path, const SceneOptions& options) {
    absl::StatusOr<std::string> text = ReadFile(path);
    if (!text.ok()) return text.status();
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    return ParseScene(*text, path, ReadBeside(parent.empty() ? "." : parent.string()), options);
}

absl::StatusOr<Scene> ParseScene(const std::string& json_text, const std::string& source,
                                 const SceneFileReader& read_file, const SceneOptions& options) {
    const bool gltf = IsGltfName(source);
    Json root;
    if (!gltf) {
        if (absl::Status status = ParseJson(json_text, source, root); !status.ok()) return status;
    }
    SceneParser parser(read_file, options);
    absl::StatusOr<Scene> scene;
    try {
        scene = gltf ? parser.ParseGltf(json_text, source) : parser.Parse(root, json_text);
        scene->source = source;
        // After every transform: tangents are not transformed with the meshes.
        ComputeMissingTangents(*scene);
    } catch (const LoadError& e) {
        scene = absl::Status(e.status.code(), absl::StrCat(source, ": ", e.status.message()));
    }
    // Also on failure: an unknown key is often the misspelling behind a missing one.
    const std::shared_ptr<spdlog::logger> logger = NamedLogger("scene");
    for (const std::string& warning : parser.warnings()) logger->warn("{}: {}", source, warning);
    if (scene.ok() && scene->dropped_degenerate > 0) {
        logger->warn("{}: dropped {} degenerate triangles (zero area or repeated vertices)", source,
                     scene->dropped_degenerate);
    }
    return scene;
}

}  // namespace lf
