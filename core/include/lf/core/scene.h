// The scene model: what a scene file describes, validated and in double precision.
// Kernels convert it once into their own representation (Embree geometry, patches).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "lf/core/medium.h"
#include "lf/core/rgb.h"
#include "lf/core/vec.h"

namespace lf {

// An image's texels, decoded once per process (lf/core/texture_io.h) and shared by every
// material and scene that uses it. Rows run from the top of the image down, so texture
// coordinate v = 0 is the top row (glTF's convention; OBJ's v is flipped on import).
struct TextureImage {
    std::string name;  // as the scene names it, for messages: "wood.png", "car.glb#image2"
    int width = 0, height = 0;
    int channels = 0;  // 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA), interleaved
    // Exactly one of these holds the texels: 8-bit files stay 8-bit (a quarter of the memory;
    // sRGB is decoded at lookup through a table), 16-bit ones become float in [0, 1] (still
    // encoded), HDR and EXR files are float radiance (`hdr`), which no sRGB curve applies to.
    std::vector<uint8_t> texels8;
    std::vector<float> texels32;
    bool hdr = false;
};

// How a material parameter reads a texture: which image, how coordinates outside [0, 1] wrap,
// whether texels are sRGB-encoded colour or linear data, and KHR_texture_transform's
// uv' = translate(offset) * rotate(rotation) * scale(scale) * uv.
struct TextureRef {
    enum class Wrap { kRepeat, kClampToEdge, kMirroredRepeat };

    int image = -1;  // index in Scene::textures; -1: no texture
    Wrap wrap_s = Wrap::kRepeat, wrap_t = Wrap::kRepeat;
    bool srgb = false;     // colour textures (base colour, emission); data textures are linear
    bool nearest = false;  // the sampler asks for nearest-texel filtering; bilinear otherwise
    Vec2 offset{0, 0};
    float rotation = 0;  // radians, counter-clockwise in uv
    Vec2 scale{1, 1};
    int tex_coord = 0;  // the uv set it reads: 0 TriangleMesh::uvs, 1 TriangleMesh::uvs1

    bool valid() const { return image >= 0; }
};

struct Material {
    // kInterface: a boundary between media that neither reflects nor refracts (rays pass
    // straight through it into the medium on the other side).
    enum class Type { kLambert, kMirror, kGlossy, kDielectric, kPrincipled, kInterface };
    enum class Distribution { kGgx, kBeckmann };
    enum class AlphaMode { kOpaque, kMask, kBlend };

    std::string name;
    Type type = Type::kLambert;
    // lambert albedo; mirror and glossy (dielectric-like) F0 tint; principled base colour
    Rgb reflectance{0.8f};
    Distribution distribution = Distribution::kGgx;
    // glossy: the microfacet alpha. principled: glTF's perceptual roughness r, GGX alpha = r^2.
    float roughness = 0.1f;
    bool conductor = false;  // glossy with complex IOR eta + i k instead of reflectance
    Rgb eta{1.0f}, k{0.0f};
    float ior = 1.5f;    // dielectric and principled: interior IOR over exterior IOR
    Rgb emission{0.0f};  // radiance leaving the front face, W m^-2 sr^-1
    // Emission leaves both faces (JSON "two_sided"), each with radiance `emission`: a panel
    // that glows on both sides emits twice the power of a one-sided one.
    bool two_sided_emission = false;
    // COLOR_0 multiplies the emission too: a KHR_materials_unlit surface emits its base colour,
    // which vertex colours multiply (glTF).
    bool emission_by_vertex_color = false;

    // The principled material: the glTF 2.0 metallic-roughness BRDF (its Appendix B) with
    // KHR_materials_transmission, _ior and _volume. Textures multiply their factors:
    // base colour (and opacity, its alpha) by `base_color_texture` (also lambert's albedo),
    // roughness by the metallic-roughness texture's G channel and metallic by its B channel,
    // emission by `emission_texture`.
    float metallic = 0;
    // Weight of the dielectric specular layer (KHR_materials_specular's factor): 0 leaves the
    // Lambertian base alone. Its colour (specularColorFactor, any value >= 0) tints the
    // layer's F0: min(F0(ior) specular_color, 1) per channel.
    float specular = 1;
    Rgb specular_color{1.0f};
    float transmission = 0;  // fraction of the dielectric base that is transmitted, not diffuse
    // KHR_materials_volume: above 0 the mesh is closed solid glass that refracts on entry and
    // exit; 0 is a thin wall that transmits without bending.
    float thickness = 0;
    Rgb attenuation_color{1.0f};  // the colour white light takes after attenuation_distance
    float attenuation_distance = std::numeric_limits<float>::infinity();  // metres
    // KHR_materials_clearcoat: a GGX dielectric layer (IOR 1.5) of this weight and perceptual
    // roughness on top of everything else.
    float clearcoat = 0;
    float clearcoat_roughness = 0;
    // KHR_materials_sheen: a cloth-like Charlie lobe of this colour and perceptual roughness
    // between the clear coat and the base; black is none.
    Rgb sheen_color{0.0f};
    float sheen_roughness = 0;
    TextureRef base_color_texture, metallic_roughness_texture, normal_texture, emission_texture;
    TextureRef transmission_texture;    // its R channel multiplies `transmission` (linear)
    TextureRef specular_texture;        // its A channel multiplies `specular` (linear)
    TextureRef specular_color_texture;  // its RGB multiplies `specular_color` (sRGB)
    // KHR_materials_clearcoat's and _sheen's textures (linear but the sheen colour): R times
    // `clearcoat`, G times `clearcoat_roughness`, RGB times `sheen_color`, A times
    // `sheen_roughness`; the coat's own normal map (without one the coat follows the
    // interpolated normal, not `normal_texture`, as the extension says).
    TextureRef clearcoat_texture, clearcoat_roughness_texture, clearcoat_normal_texture;
    float clearcoat_normal_scale = 1;
    TextureRef sheen_color_texture, sheen_roughness_texture;
    float normal_scale = 1;  // scales the normal map's x and y (glTF normalTexture.scale)
    float opacity = 1;       // base colour alpha factor; with the texture's alpha, for kMask
    // kBlend (glTF BLEND): stochastic transparency, rays pass through with probability
    // 1 - opacity, so the image converges to opacity * surface + (1 - opacity) * behind.
    AlphaMode alpha_mode = AlphaMode::kOpaque;
    float alpha_cutoff = 0.5f;  // kMask: opacity below this is a hole
    // Single-sided surfaces (glTF doubleSided false) are invisible from behind, as in glTF
    // viewers, unless the material transmits (its back faces are where light leaves).
    bool double_sided = true;

    bool IsEmissive() const { return !emission.IsBlack(); }
    // A closed solid whose inside light travels through: a dielectric, or a principled
    // transmitter with a thickness (KHR_materials_volume). Its attenuation is its interior
    // medium's absorption (Scene::media).
    bool HasInterior() const {
        return type == Type::kDielectric ||
               (type == Type::kPrincipled && transmission > 0 && thickness > 0);
    }
    // Whether rays can hit the back face: double-sided, or a transmitter whose back faces are
    // where light leaves it. Only then can two_sided_emission emit from the back.
    bool VisibleFromBehind() const {
        return double_sided || type == Type::kDielectric ||
               (type == Type::kPrincipled && transmission > 0);
    }
    std::array<const TextureRef*, 12> Textures() const {
        return {
            &base_color_texture,       &metallic_roughness_texture, &normal_texture,
            &emission_texture,         &transmission_texture,       &specular_texture,
            &specular_color_texture,   &clearcoat_texture,          &clearcoat_roughness_texture,
            &clearcoat_normal_texture, &sheen_color_texture,        &sheen_roughness_texture};
    }
    bool IsTextured() const {
        for (const TextureRef* t : Textures()) {
            if (t->valid()) return true;
        }
        return false;
    }
    // Whether a texture reads the second uv set (TriangleMesh::uvs1).
    bool ReadsUvs1() const {
        for (const TextureRef* t : Textures()) {
            if (t->valid() && t->tex_coord == 1) return true;
        }
        return false;
    }
};

const char* MaterialTypeName(Material::Type type);

// Quads, triangles and meshes all become triangle meshes. Front face normal of triangle
// (v0, v1, v2) is normalize((v1 - v0) x (v2 - v0)).
struct TriangleMesh {
    std::string name;
    int material = 0;
    std::vector<Vec3d> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    // Per-vertex attributes, each empty or as long as positions. Without normals the mesh is
    // flat-shaded; tangents (xyz, and w = ±1 the bitangent's sign) serve normal maps.
    std::vector<Vec3> normals;  // unit, in the same space as positions
    std::vector<Vec2> uvs;      // TEXCOORD_0: v = 0 is the top of the image
    // TEXCOORD_1, for textures with tex_coord 1; loaders keep it only when the material reads it.
    std::vector<Vec2> uvs1;
    std::vector<std::array<float, 4>> tangents;
    // COLOR_0, linear RGBA: multiplies the base colour and its alpha the opacity (glTF).
    std::vector<std::array<float, 4>> colors;
    // True when the mesh came from a `quad` shape: (v0,v1,v2),(v0,v2,v3). Radiosity meshes
    // such shapes as a grid of quads rather than triangles.
    bool is_quad = false;
    MediumInterface media;  // JSON "interior" and "exterior"

    // The uv set a texture with this tex_coord reads.
    const std::vector<Vec2>& Uvs(int tex_coord) const { return tex_coord == 1 ? uvs1 : uvs; }
};

struct Sphere {
    std::string name;
    int material = 0;
    Vec3d center;
    double radius = 1;
    MediumInterface media;
};

struct PointLight {
    Vec3d position;
    Rgb intensity;  // W/sr per channel
};

// A point light whose intensity falls off between two cones around `direction`: full inside
// inner_cone, zero outside outer_cone. Between them, with c = cos(angle to the axis):
//  - kSmoothstep (JSON scenes, pbrt-v4's SpotLight): smoothstep(cos outer, cos inner, c);
//  - kKhrLightsPunctual (glTF): KHR_lights_punctual's clamp((c - cos outer) /
//    (cos inner - cos outer), 0, 1)^2, so glTF scenes look as their authors saw them.
struct SpotLight {
    enum class Falloff { kSmoothstep, kKhrLightsPunctual };

    Vec3d position;
    Vec3d direction;                           // unit, the way the light points
    Rgb intensity;                             // W/sr per channel on the axis
    double inner_cone = 0;                     // radians, half-angle
    double outer_cone = 3.14159265358979 / 4;  // radians, half-angle, > inner_cone
    Falloff falloff = Falloff::kSmoothstep;
};

// Light from far away along `direction`. With angular_diameter 0 a delta light (parallel rays,
// sharp shadows); above 0 a disk of that apparent diameter (the sun: about 0.53 degrees) of
// uniform radiance irradiance / (pi sin^2(angular_diameter / 2)), so a surface facing it
// receives `irradiance` either way and shadows get penumbrae.
struct DirectionalLight {
    Vec3d direction;              // unit, the way the light travels
    Rgb irradiance;               // W/m^2 per channel on a surface facing the light
    double angular_diameter = 0;  // radians, full apex angle of the cone, in [0, pi/2]
};

// Light arriving from every direction at infinity (a sky). Without a map its radiance is
// `radiance` everywhere; with one, the map's texel times `radiance` (which carries the scene's
// `scale` or photometric normalisation). The map is latitude-longitude with +y up, oriented as
// Blender's Environment Texture in a glTF export: world direction d is first turned by
// +rotate_y about +y (as Blender's Mapping node, type Point, turns the direction it reads by
// its Z rotation, so the sky turns clockwise seen from above), then read at
// u = 0.5 + atan2(d.z, d.x) / (2 pi), v = acos(d.y) / pi, texel row 0 at the top (v = 0).
struct EnvironmentLight {
    Rgb radiance{1.0f};                       // W m^-2 sr^-1 per channel (times the map's texel)
    std::shared_ptr<const TextureImage> map;  // HDR/EXR texels, linear; null: uniform
    double rotate_y = 0;                      // radians
};

// How each sample is placed in its pixel: box (the seeds' sensor: uniform over the pixel
// square) or, by filter importance sampling (pbrt-v4), at an offset drawn from the filter's
// own distribution, so every sample keeps weight 1 and sums stay exact. `width` is the filter's
// full support in pixels (box: 1 only; gaussian: sigma = width / 6; blackman-harris: the
// window's length). Separable: x and y offsets are drawn independently.
struct PixelFilter {
    enum class Type { kBox, kGaussian, kBlackmanHarris };
    Type type = Type::kBox;
    double width = 1;
};

struct CameraSpec {
    // Perspective: rays leave `position` through a film of vertical angle fov_y_deg.
    // Orthographic (glTF's xmag/ymag): parallel rays along the view axis from a film
    // 2 half_height tall (scene units) centred on `position`, as wide as the image's aspect.
    enum class Projection { kPerspective, kOrthographic };
    Projection projection = Projection::kPerspective;
    Vec3d position{0, 0, 0};
    Vec3d look_at{0, 0, 1};
    Vec3d up{0, 1, 0};
    double fov_y_deg = 45;
    double half_height = 1;  // orthographic only
    int width = 256;
    int height = 256;
    // Thin lens (distributed ray tracing): rays leave a disk of this radius around `position`,
    // perpendicular to the view, and meet again on the plane focus_distance along the view axis.
    // 0: a pinhole, everything sharp.
    double aperture_radius = 0;
    double focus_distance = 1;  // scene units; used only with an aperture
    PixelFilter filter;
};

// Beyond this a coordinate is a unit mistake or garbage, and the float kernels would have no
// precision left for the geometry's detail (and above 3.4e38 none at all: Embree aborts on an
// infinite ray).
inline constexpr double kMaxCoordinate = 1e15;

struct SceneAnimation;  // lf/core/scene_animation.h

struct Scene {
    CameraSpec camera;
    std::vector<Material> materials;
    std::vector<TriangleMesh> meshes;
    std::vector<Sphere> spheres;
    std::vector<PointLight> point_lights;
    std::vector<SpotLight> spot_lights;
    std::vector<DirectionalLight> directional_lights;
    std::optional<EnvironmentLight> environment;  // at most one sky
    // Images the materials' TextureRefs index; shared, so a copied scene costs no texels.
    std::vector<std::shared_ptr<const TextureImage>> textures;
    // Participating media (JSON "media"), which shapes' MediumInterfaces and camera_medium
    // index. Solid transmitters with KHR_materials_volume's attenuation get a homogeneous
    // absorbing medium here as their interior.
    std::vector<Medium> media;
    int camera_medium = -1;  // the medium the camera sits in (JSON camera "medium"), -1 vacuum

    std::string source;        // path of the scene file, for messages
    std::string content_hash;  // hex digest of the scene file and every mesh file it names
    int dropped_degenerate = 0;
    // What glTF animations, skins and morph targets do to this scene over time (PoseAt); null
    // when the scene has none. The geometry above is the files' rest pose until posed.
    std::shared_ptr<const SceneAnimation> animation;
    // Not ok when the files' animation data is malformed: a still loads (with a warning) and
    // renders the rest pose; whoever needs the scene in time (frames, a shutter) refuses with it.
    absl::Status animation_error;

    // Axis-aligned bounds of all geometry.
    std::pair<Vec3d, Vec3d> Bounds() const;
    bool HasLights() const;  // any emitter: emissive material or a light of any kind
    // Any medium, a camera inside one or an interface surface: what the volumetric path tracer
    // renders and the other methods refuse (but Beer's-law absorbers, which they take).
    bool HasMedia() const;
};

// Beer's law as a medium: each solid transmitter (Material::HasInterior) with a finite
// attenuation_distance and no interface of its own gets a homogeneous absorber inside (its
// exterior the camera's medium, vacuum or fog), sigma_a = -ln(attenuation_color) / attenuation_distance, one per material. Every
// loader calls it; scenes built in code call it themselves.
void AddAttenuationMedia(Scene& scene);

// InvalidArgument naming the first position (vertex, sphere, light, camera) beyond
// ±kMaxCoordinate or not finite, or direction not finite. Every loader ends with it, so whoever
// loads a scene (a worker included) never hands such numbers to the kernels, whoever checked it
// before.
absl::Status CheckCoordinates(const Scene& scene);

}  // namespace lf
