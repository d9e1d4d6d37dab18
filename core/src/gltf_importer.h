// GltfImporter: one glTF file, as tinygltf parsed it, into the scene model. Its members are
// defined by concept: gltf_nodes.cc (the node tree, cameras and lights), gltf_meshes.cc
// (accessors and primitives) and gltf_materials.cc (materials, textures and images); AppendGltf
// (gltf_scene.cc) loads the file and runs it. Private to core.
#pragma once

#include <tiny_gltf.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "lf/core/affine.h"
#include "lf/core/gltf_scene.h"
#include "lf/core/scene.h"
#include "lf/core/texture.h"

namespace lf::gltf_internal {

inline std::string Quoted(const std::string& name) {
    return name.empty() ? std::string() : absl::StrCat(" \"", name, "\"");
}

// An error unwinds to AppendGltf as this, which adds the file name.
struct GltfError {
    std::string message;
};

[[noreturn]] inline void Fail(const std::string& where, const std::string& message) {
    throw GltfError{absl::StrCat(where, ": ", message)};
}

// One accessor's elements, checked to lie inside their buffer view and buffer.
struct AccessorData {
    const unsigned char* data = nullptr;
    size_t stride = 0, count = 0;
    int components = 0, component_type = 0, component_size = 0;
    bool normalized = false;
};

// What one Draco primitive may decode to (a few GB at most), refused beyond.
inline constexpr size_t kMaxDracoPoints = size_t(1) << 26, kMaxDracoFaces = size_t(1) << 26;

// tinygltf 2.7 refuses a primitive whose indices accessor has no bufferView, which a Draco
// primitive's need not have: the glTF (`binary`: .glb) with each Draco primitive's "indices"
// moved into its extension object, where DecodeDraco reads it. Other files come back as they are.
std::string PrepareDraco(const std::string& bytes, bool binary);

// A node's rest translation, rotation (normalised; Fail naming `where` for the zero
// quaternion) and scale, and its whole local transform (its matrix, checked) (gltf_nodes.cc).
Vec3d NodeTranslation(const tinygltf::Node& node);
std::array<double, 4> NodeRotation(const tinygltf::Node& node, const std::string& where);
Vec3d NodeScale(const tinygltf::Node& node);
Affine LocalTransform(const tinygltf::Node& node, const std::string& where);

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

    // The default scene: its nodes' meshes, cameras and lights (gltf_nodes.cc).
    void Import();

  private:
    void Warn(const std::string& message) { warnings_.push_back(message); }
    // A loss that many objects may share, warned once at the end with their count:
    // "occlusionTexture ignored (...) in 12 materials: materials[0] \"a\", ...".
    void Tally(const std::string& what, const std::string& noun, const std::string& where) {
        Tallied& t = tallies_[what];
        t.noun = noun;
        t.wheres.push_back(where);
    }
    void WarnTallies();

    void CheckExtensions();
    void VisitNode(int index, const Affine& parent, const std::string& ref);
    void AddCamera(const tinygltf::Node& node, const Affine& world, const std::string& where);
    void AddLight(const tinygltf::Value& light_index, const Affine& world,
                  const std::string& where);

    // Animations, skins and morph targets into options_.animation (gltf_animations.cc).
    // Whether the file has any (else the import collects nothing).
    bool Animates() const;
    // Runs `step` of reading the animation while animating_. A fault in it (a GltfError) drops
    // the file's animation but not the file: one warning ("animation ignored: ..."), the error
    // in options_.animation_error, and no further steps.
    void AnimationStep(const std::function<void()>& step);
    // Every node into the animation's tree, parents first, and every channel.
    void ReadNodeTree();
    void ReadAnimations();
    // How many scene objects there were before node `index` added its own.
    struct Counts {
        size_t cameras, point_lights, spot_lights, directional_lights;
    };
    Counts CountObjects() const;
    // Records what node `index` added since `before`: its camera's node, its lights when they
    // move.
    void AnimateNode(int index, const Counts& before);
    // Records scene mesh `scene_mesh`, primitive `primitive` of node `node`'s mesh: its rest
    // geometry, skin and morph targets. Called while decoded_ holds the primitive's Draco data.
    void AnimateMesh(int node, int scene_mesh, int primitive, const std::string& node_where);
    int Skin(int index, const std::string& node_where);

    // Meshes (gltf_meshes.cc).
    // A buffer view's bytes, checked to lie inside their buffer.
    std::string_view BufferView(int index, const std::string& where);
    // What accessor `index` declares (type, count), without its data.
    AccessorData Declaration(int index, const std::string& where);
    // Accessor `index`'s elements: decoded_'s when the primitive is Draco's, else the buffer's.
    AccessorData Accessor(int index, const std::string& where);
    // An attribute's elements as floats, `components` per element: FLOAT, or the normalized
    // integer types glTF allows for texture coordinates and colours. Not finite values are
    // refused unless `any_value` (animation samplers: Keyframes::Create names their key).
    std::vector<float> Floats(int index, int components, const std::string& where,
                              bool any_value = false);
    std::vector<uint32_t> Indices(int index, size_t vertices, const std::string& where);
    // Node `node`'s mesh, one scene mesh per triangle primitive, each recorded for the
    // animation when the import collects one.
    void AddMesh(int node, const Affine& world, const std::string& node_where);
    // Decodes a KHR_draco_mesh_compression primitive into decoded_ (gltf_draco.cc); returns
    // its indices accessor.
    int DecodeDraco(const tinygltf::Primitive& primitive, const tinygltf::Value& draco,
                    const std::string& where);

    // Materials, textures and images (gltf_materials.cc).
    // The scene material for glTF material `index` (-1: glTF's default material).
    int Material(int index, const std::string& where);
    // glTF's default: white, fully metallic and rough, opaque, single-sided.
    lf::Material DefaultMaterial() const;
    static double Number(const tinygltf::Value& object, const char* key, double fallback, double lo,
                         double hi, const std::string& where);
    static std::vector<double> Numbers(const tinygltf::Value& object, const char* key,
                                       std::vector<double> fallback, const std::string& where);
    static Rgb Color(const std::vector<double>& v, const std::string& where, const char* key);
    static const tinygltf::Value* Extension(const tinygltf::ExtensionMap& map, const char* key);
    lf::Material ConvertMaterial(int index);
    // KHR_materials_unlit: `m` emits its base colour (factor times texture) and reflects nothing.
    static void MakeUnlit(lf::Material& m);
    // The TextureRef of a material's texture slot; `srgb` for colour textures.
    TextureRef Texture(int index, int tex_coord, const tinygltf::ExtensionMap& extensions,
                       bool srgb, const std::string& where);
    // The TextureRef of an extension's textureInfo `key` (e.g. transmissionTexture); none when
    // absent.
    TextureRef TextureInfo(const tinygltf::Value& extension, const char* key, bool srgb,
                           const std::string& where);
    static TextureRef::Wrap Wrap(int mode, const std::string& where);
    // The Scene::textures index of glTF image `index`, decoded once however many textures
    // use it.
    int Image(int index);

    const tinygltf::Model& model_;
    const std::string& name_;
    const GltfImport& options_;
    Scene& scene_;
    std::vector<GltfCamera>& cameras_;
    std::vector<std::string>& warnings_;
    const std::map<int, absl::StatusOr<std::shared_ptr<const TextureImage>>>& images_;
    const std::map<std::string, absl::Status>& read_errors_;
    struct Tallied {
        std::string noun;
        std::vector<std::string> wheres;
    };
    std::map<std::string, Tallied> tallies_;
    std::vector<bool> visited_;
    // Whether the import collects the file's animation (it has one and nothing failed yet).
    bool animating_ = false;
    // Animation: each glTF node's and skin's index in options_.animation (-1: none).
    std::vector<int> node_of_;
    std::map<int, int> skin_of_;
    std::vector<bool> moving_;  // SceneAnimation::MovingNodes once the channels are read
    std::map<int, int> material_of_, texture_of_;
    // The current primitive's Draco-decoded accessors, by accessor index: AddMesh records each
    // primitive for the animation (AnimateMesh) before it decodes the next.
    struct Decoded {
        std::vector<unsigned char> bytes;
        AccessorData data;
    };
    std::map<int, Decoded> decoded_;
    bool range_ignored_ = false;
};

}  // namespace lf::gltf_internal
