// SceneParser: a JSON scene, or a glTF file as a whole scene, into the scene model. Its members
// are defined by concept: scene_loader.cc (the whole scene), scene_camera.cc, scene_materials.cc,
// scene_shapes.cc, scene_keyframes.cc (keyframed transforms), scene_lights.cc (lights and
// photometric units) and scene_media.cc (participating media). Private to core.
#pragma once

#include <array>
#include <functional>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "fnv1a128.h"
#include "lf/core/affine.h"
#include "lf/core/gltf_scene.h"
#include "lf/core/mesh_io.h"
#include "lf/core/pixel_filter.h"
#include "lf/core/scene.h"
#include "lf/core/scene_loader.h"
#include "lf/core/texture.h"
#include "scene_json.h"

namespace lf::scene_internal {

// A mesh file's meshes as a scene uses them.
struct CachedMeshFile {
    std::vector<TriangleMesh> meshes;
    std::string unassigned_where;  // where faces without a material are, when they need one
};

class SceneParser {
  public:
    SceneParser(const SceneFileReader& read_file, const SceneOptions& options)
        : read_file_(read_file), options_(options) {}

    Scene Parse(const Json& json, const std::string& text);

    // A glTF file as the whole scene: its camera, or the one options_.camera names.
    Scene ParseGltf(const std::string& bytes, const std::string& source);

    const std::vector<std::string>& warnings() const { return warnings_; }

  private:
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

    // The whole scene (scene_loader.cc).
    Scene Finish(Scene& scene);
    static bool IncludesGltf(const Node& root);
    // The JSON's camera unless --camera names a glTF one; the first glTF camera without either.
    // `--camera auto`, or the scene's camera of that name.
    void ResolveCamera(const Node& root, bool json_camera, Scene& scene);
    // `--camera auto` and no glTF camera of that name: FrameScene.
    bool FramesTheScene() const;
    // The glTF camera options_.camera names (the first without a name) as the scene's camera,
    // its node the one the animation poses; LoadError as ChooseGltfCamera says, after `prefix`.
    void UseGltfCamera(const std::string& prefix, Scene& scene);

    // Camera (scene_camera.cc).
    CameraSpec ParseCamera(const Node& n);
    // {"type": "box" | "gaussian" | "blackman-harris", "width": pixels}. Without a width: 1 for
    // the box, 3 for the others (pbrt-v4's default Gaussian, sigma 0.5 pixel, radius 1.5).
    static PixelFilter ParseFilter(const Node& n);

    // Materials and textures (scene_materials.cc).
    Material ParseMaterial(const std::string& name, const Node& n);
    // `emission` (W m^-2 sr^-1), `luminance_nits` or `power_lm` with their colour, and
    // `two_sided`. power_lm waits for every shape (ResolveEmittedPower): it is spread over them.
    void ParseEmission(const Node& n, Material& m);
    // Lambert's albedo and principled's base colour: `base_color` or its older name
    // `reflectance`, times `base_color_texture` when given. Without a texture the colour is
    // required; with one it defaults to white, the texture alone.
    void ParseBaseColor(const Node& n, Material& m);
    // glTF 2.0's metallic-roughness material; defaults as Blender's Principled BSDF.
    void ParsePrincipled(const Node& n, Material& m);
    // A texture: a file name, or {"file", "wrap", "filter", "transform"}.
    TextureRef ParseTexture(const Node& n, bool srgb);
    // The index in Scene::textures of image file `name`, read and decoded once per scene.
    // `where` (a JSON path, an MTL file's line) starts messages.
    int TextureIndex(const std::string& name, const std::string& where);
    // Image file `name`, read through the scene's reader (so `submit` uploads it) and hashed.
    std::shared_ptr<const TextureImage> DecodeFile(const std::string& name,
                                                   const std::string& where);

    // Shapes and included files (scene_shapes.cc).
    void ParseShape(const Node& n, Scene& scene);
    // A fixed `transform`: {"scale", "rotate", "translate"} or {"matrix"}.
    static Affine ParseTransform(const Node& n);
    // `rotate`, {"axis": [x, y, z], "angle_deg": a}, as a unit quaternion (x, y, z, w):
    // counter-clockwise looking down the axis at the origin (right-hand rule).
    static std::array<double, 4> ParseRotation(const Node& rotate);
    // A mesh file's meshes, in the file's coordinates: with `material_index` (>= 0) one mesh
    // of that material, otherwise one per material of the file (an OBJ's MTL files), those
    // materials added to the scene.
    std::vector<TriangleMesh> LoadMeshShape(const Node& n, int material_index, Scene& scene);

    // Keyframed transforms (scene_keyframes.cc).
    // What a transform may do to the object it places: spheres stay spheres, cameras keep
    // their lens.
    enum class Scaling { kAny, kUniform, kNone };
    // A `transform`, fixed or keyframed ({"keyframes": [...], "interpolation": ...}): where
    // the object is in a still (`rest`: a keyframed transform's first keyframe) and, when
    // keyframed, the animation node it became (`node`, else -1), named `where` in messages.
    struct PlacedTransform {
        Affine rest;
        int node = -1;
    };
    PlacedTransform ParseAnyTransform(const Node& n, Scaling scaling, const std::string& where);
    // The node of a keyframed transform `n`, its channels, and its first keyframe's transform.
    PlacedTransform ParseKeyframes(const Node& n, Scaling scaling, const std::string& where);
    // A mesh file's materials join the scene's, their textures its textures; the meshes'
    // material indices become the scene's.
    CachedMeshFile AddFileMaterials(MeshFile file, const std::string& where, Scene& scene);
    // Appends glTF `name` (read as `bytes`) to `scene`, every file it reads hashed, its meshes
    // checked as a JSON mesh's are. `fail` throws the error with the caller's context. Warnings
    // name the glTF when it is included (the log line names the scene file already).
    void ImportGltf(const std::string& bytes, const std::string& name, const std::string& base_dir,
                    const Affine& transform, Scene& scene,
                    const std::function<void(const absl::Status&)>& fail, bool included);
    // {"type": "gltf", "file": ..., "transform": ...}: a glTF file's meshes, materials, lights
    // and cameras in a JSON scene.
    void ParseGltfShape(const Node& n, Scene& scene);

    // Lights and photometric units (scene_lights.cc).
    void ParseLight(const Node& n, Scene& scene);
    SpotLight ParseSpot(const Node& n);
    EnvironmentLight ParseEnvironment(const Node& n);
    // A lat-long map for the sky: an HDR or EXR file (an 8- or 16-bit image is refused).
    std::shared_ptr<const TextureImage> DecodeSkyMap(const std::string& name,
                                                     const std::string& where);
    // options_.sky as the scene's environment light, replacing its own with a warning.
    void ApplySky(Scene& scene);
    // The luminance (Rec.709 Y) of a lat-long map times `tint`, averaged over the sphere of
    // directions: each texel weighs its solid angle, (cos theta_top - cos theta_bottom) of its
    // row times 2 pi / width, its radiance taken as constant over it.
    static double MeanLuminance(const TextureImage& map, const Rgb& tint);
    // A unit direction from a non-zero vector.
    static Vec3d Direction(const Node& n);
    // The one strength of `keys` that light `n` gives; none (when not `required`) or several
    // are errors.
    static std::optional<Strength> FindStrength(const Node& n,
                                                std::initializer_list<StrengthKey> keys,
                                                bool required);
    // A strength as the radiometric quantity the scene model keeps (W/sr, W/m^2 or
    // W m^-2 sr^-1 per channel). Radiometric: [r, g, b], or a number times the light's colour.
    // Photometric: a number times the colour at luminance 1, at 683 lm/W.
    static Rgb StrengthValue(const Node& light, const Strength& strength);
    // A light's intensity in W/sr: given, or its power over `solid_angle` (the light's emission
    // integrated over directions, relative to its peak), radiometric or photometric.
    static Rgb RadiantIntensity(const Node& n, double solid_angle);
    // A light's or emitter's colour: `color` or `temperature_k` (a black body, luminance 1),
    // white by default. With a photometric strength `color` is scaled to luminance 1, so the
    // strength alone sets the luminous quantity.
    static Rgb LightColor(const Node& light, bool photometric);
    // Each power_lm material's luminance: its power over the area of every shape using it, out
    // of one face (pi L A) or both (2 pi L A).
    void ResolveEmittedPower(Scene& scene);

    // Participating media (scene_media.cc).
    // The top-level "media" object into Scene::media.
    void ParseMedia(const Node& media, Scene& scene);
    Medium ParseMedium(const std::string& name, const Node& n);
    // Grid `grid_name` (named at `key`) of a grid medium's `file`, the file read and hashed once.
    std::shared_ptr<const VolumeGrid> LoadGrid(const Node& file, const Node& key,
                                               const std::string& grid_name,
                                               const Affine& transform);
    // A shape's "interior" and "exterior": either makes an interface, the other side vacuum.
    MediumInterface ParseMediumInterface(const Node& shape) const;
    // The index in Scene::media of the medium named at `n`.
    int MediumIndex(const Node& n) const;

    const SceneFileReader& read_file_;
    const SceneOptions& options_;
    std::vector<GltfCamera> gltf_cameras_;
    // The node placing the JSON camera when it has keyframes; -1: it stays.
    int json_camera_node_ = -1;
    // Every included glTF's animations, skins and morphs; the Scene gets it unless it is empty
    // or a file's animation data is malformed (animation_error_, the first such fault).
    SceneAnimation animation_;
    absl::Status animation_error_;
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
    std::map<std::string, int> texture_index_;       // by file name, into *textures_
    std::map<std::string, int> medium_index_;        // by name, into Scene::media
    std::map<std::string, std::string> grid_files_;  // .vdb bytes by normalised name
    std::vector<std::shared_ptr<const TextureImage>>* textures_ = nullptr;  // the scene's
    Fnv1a128 hash_;
    int dropped_degenerate_ = 0;
};

}  // namespace lf::scene_internal
