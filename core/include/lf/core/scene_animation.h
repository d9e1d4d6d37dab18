// A scene in time: what glTF animations, skins and morph targets do to a loaded Scene. The
// loader keeps the node tree's rest pose, its animation channels and, for every Scene object a
// node drives, which node and (for meshes) the geometry in the mesh's own space, so the same
// Scene can be re-posed at any time without reloading. docs/architecture.md ("The scene in
// time") describes the design.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "lf/core/affine.h"
#include "lf/core/keyframes.h"
#include "lf/core/scene.h"

namespace lf {

// A node of the tree, in rest pose. Parents come before their children.
struct AnimationNode {
    std::string where;  // for messages: "nodes[3] \"Arm\"" (with the glTF's name when included)
    int parent = -1;    // index in SceneAnimation::nodes; -1: a root, placed by `root`
    Affine root;        // roots only: the transform above the file (a JSON scene's "transform")
    // A node given by a matrix keeps it (channels cannot target it); others compose
    // translation * rotation * scale, any of which a channel may replace.
    bool has_matrix = false;
    Affine matrix;
    Vec3d translation{0, 0, 0};
    std::array<double, 4> rotation{0, 0, 0, 1};  // unit quaternion (x, y, z, w)
    Vec3d scale{1, 1, 1};
    std::vector<double> weights;  // the node's morph weights, empty: its mesh's
};

struct AnimationChannel {
    enum class Path { kTranslation, kRotation, kScale, kWeights };
    int node = 0;  // index in SceneAnimation::nodes
    Path path = Path::kTranslation;
    Keyframes keys;
};

// glTF's skin: vertex v goes to sum_i w_i (world(joint_i) * inverse_bind_i) v; the node that
// holds the mesh does not move it.
struct AnimationSkin {
    std::vector<int> joints;  // indices in SceneAnimation::nodes
    std::vector<Affine> inverse_bind;
};

// A morph target's per-vertex displacements; each empty when the target has none.
struct MorphTarget {
    std::vector<Vec3d> positions;
    std::vector<Vec3d> normals, tangents;
};

// A Scene mesh a node drives, with its geometry in the mesh's own space (the glTF accessors).
struct AnimatedMesh {
    int mesh = 0;  // index in Scene::meshes
    int node = 0;  // index in SceneAnimation::nodes
    std::vector<Vec3d> positions;
    std::vector<Vec3d> normals;                   // empty: the mesh has none
    std::vector<std::array<double, 4>> tangents;  // empty: none in the file (the loader's
                                                  // ComputeMissingTangents makes them anew)
    std::vector<MorphTarget> targets;
    std::vector<double> weights;  // the mesh's default weights (glTF mesh.weights; else 0)
    int skin = -1;                // index in SceneAnimation::skins; -1: rigid
    // Skinned: `influences` (4 or 8) joint indices in the skin and weights per vertex.
    int influences = 0;
    std::vector<uint32_t> joints;
    std::vector<double> joint_weights;
    bool moves = false;  // a channel changes it over time (rigidly or by deformation)
};

// A light a node places: Scene::point_lights[index], spot_lights[index] or
// directional_lights[index].
struct AnimatedLight {
    enum class Kind { kPoint, kSpot, kDirectional };
    Kind kind = Kind::kPoint;
    int index = 0;
    int node = 0;
    bool moves = false;
};

// A Scene sphere a node places (a JSON sphere with keyframes): its centre moved by the node's
// world transform, its radius scaled by the transform's scale, which the loader keeps uniform.
struct AnimatedSphere {
    int sphere = 0;  // index in Scene::spheres
    int node = 0;    // index in SceneAnimation::nodes
    Vec3d center;    // in the node's space
    double radius = 1;
    bool moves = false;
};

struct SceneAnimation {
    std::vector<AnimationNode> nodes;
    // Every animation of every file, and every JSON keyframed transform, all at once.
    std::vector<AnimationChannel> channels;
    std::vector<AnimationSkin> skins;
    std::vector<AnimatedMesh> meshes;
    std::vector<AnimatedSphere> spheres;
    std::vector<AnimatedLight> lights;
    // The node of the Scene's camera when it is a glTF camera or a JSON camera with keyframes
    // (a child node placing it as a glTF camera: looking down -Z, +Y up); -1: it stays.
    int camera_node = -1;

    // Writes the world-space geometry (meshes and spheres), camera and lights of time
    // `seconds` into `scene`, the Scene this animation was loaded with (or a copy of it). Only
    // what a node drives is written; the camera keeps its lens, resolution and filter.
    // InvalidArgument naming the node and the time when a pose flattens a transform or leaves
    // the coordinate range (±kMaxCoordinate).
    absl::Status PoseAt(double seconds, Scene& scene) const;

    // Each node's world transform at `seconds`.
    std::vector<Affine> WorldTransforms(double seconds) const;

    // For each node, whether a translation, rotation or scale channel moves it or one of its
    // ancestors.
    std::vector<bool> MovingNodes() const;
    // Whether anything in the scene changes over time; false: every time gives one image.
    bool Moves() const;
    // The first and last keyframe times of all channels (0, 0 without channels).
    double Start() const;
    double End() const;
    // Whether the animation drives anything at all (skins and morph weights pose a mesh even
    // without channels).
    bool Empty() const {
        return meshes.empty() && spheres.empty() && lights.empty() && camera_node < 0;
    }
};

// Places `spec` (position, look_at, up) where a glTF camera node with world transform `world`
// is: looking down its -Z with +Y up. False when the transform flattens the view.
bool PlaceGltfCamera(const Affine& world, CameraSpec& spec);

}  // namespace lf
