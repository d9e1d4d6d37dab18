#include "lf/core/scene_animation.h"

#include <algorithm>
#include <cmath>
#include <span>

#include "absl/strings/str_cat.h"
#include "lf/core/mesh_tangents.h"

namespace lf {
namespace {

// A weighted sum of affine maps (linear blend skinning's per-vertex matrix).
void AddScaled(const Affine& a, double weight, Affine& sum) {
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) sum.m[r][c] += weight * a.m[r][c];
    }
}

// Within the coordinate range every loader checks (and finite).
bool InRange(const Vec3d& p) {
    return std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate &&
           std::abs(p.z) <= kMaxCoordinate;
}

std::string Beyond(const Vec3d& p) {
    return absl::StrCat("(", p.x, ", ", p.y, ", ", p.z, ") is beyond ±", kMaxCoordinate);
}

Affine Zero() {
    Affine z;
    for (auto& row : z.m) row.fill(0);
    return z;
}

// The morph weights of `mesh` at this pose: a weights channel's, else the node's, else the
// mesh's own.
std::span<const double> MorphWeights(const AnimatedMesh& mesh, const AnimationNode& node,
                                     const std::vector<std::vector<double>>& animated) {
    const std::vector<double>& channel = animated[size_t(mesh.node)];
    if (!channel.empty()) return channel;
    if (!node.weights.empty()) return node.weights;
    return mesh.weights;
}

absl::Status PoseMesh(const AnimatedMesh& a, const SceneAnimation& animation,
                      const std::vector<Affine>& world,
                      const std::vector<std::vector<double>>& weights, double seconds,
                      Scene& scene) {
    TriangleMesh& mesh = scene.meshes[size_t(a.mesh)];
    const std::string& where = animation.nodes[size_t(a.node)].where;
    const size_t n = a.positions.size();
    if (mesh.positions.size() != n) {
        return absl::InternalError(absl::StrCat(where, ": mesh \"", mesh.name, "\" has ",
                                                mesh.positions.size(), " vertices, its rest pose ",
                                                n));
    }
    const std::span<const double> w = MorphWeights(a, animation.nodes[size_t(a.node)], weights);
    std::vector<Affine> joint_matrices;
    if (a.skin >= 0) {
        const AnimationSkin& skin = animation.skins[size_t(a.skin)];
        for (size_t j = 0; j < skin.joints.size(); ++j) {
            joint_matrices.push_back(skin.inverse_bind[j].Then(world[size_t(skin.joints[j])]));
        }
    }
    const Affine& rigid = world[size_t(a.node)];
    const Affine rigid_normals = rigid.NormalMatrix();
    for (size_t v = 0; v < n; ++v) {
        Vec3d p = a.positions[v];
        Vec3d normal = a.normals.empty() ? Vec3d() : a.normals[v];
        Vec3d tangent = a.tangents.empty()
                            ? Vec3d()
                            : Vec3d(a.tangents[v][0], a.tangents[v][1], a.tangents[v][2]);
        for (size_t t = 0; t < a.targets.size() && t < w.size(); ++t) {
            if (w[t] == 0) continue;
            const MorphTarget& target = a.targets[t];
            if (!target.positions.empty()) p += w[t] * target.positions[v];
            if (!target.normals.empty() && !a.normals.empty()) normal += w[t] * target.normals[v];
            if (!target.tangents.empty() && !a.tangents.empty()) {
                tangent += w[t] * target.tangents[v];
            }
        }
        Affine m = rigid;
        if (a.skin >= 0) {
            m = Zero();
            for (int i = 0; i < a.influences; ++i) {
                const size_t k = v * size_t(a.influences) + size_t(i);
                if (a.joint_weights[k] != 0) {
                    AddScaled(joint_matrices[a.joints[k]], a.joint_weights[k], m);
                }
            }
        }
        mesh.positions[v] = m.Apply(p);
        if (!InRange(mesh.positions[v])) {
            return absl::InvalidArgumentError(absl::StrCat(where, " at ", seconds, " s: mesh \"",
                                                           mesh.name, "\" vertex ", v, " at ",
                                                           Beyond(mesh.positions[v])));
        }
        if (!a.normals.empty()) {
            const Vec3d moved =
                (a.skin >= 0 ? m.NormalMatrix() : rigid_normals).ApplyLinear(normal);
            const double length = Length(moved);
            // A vertex a pose collapses keeps its last normal rather than none.
            if (length > 0) mesh.normals[v] = Vec3(moved / length);
        }
        if (!a.tangents.empty()) {
            const Vec3d moved = m.ApplyLinear(tangent);
            const double length = Length(moved);
            if (length > 0) {
                const Vec3 unit(moved / length);
                const float sign =
                    float(a.tangents[v][3] < 0 ? -1 : 1) * (m.Determinant() < 0 ? -1.0f : 1.0f);
                mesh.tangents[v] = {unit.x, unit.y, unit.z, sign};
            }
        }
    }
    // Tangents the loader made for a normal map follow the posed surface.
    if (a.tangents.empty() && !mesh.tangents.empty()) {
        mesh.tangents.clear();
        ComputeTangents(mesh);
    }
    return absl::OkStatus();
}

}  // namespace

bool PlaceGltfCamera(const Affine& world, CameraSpec& spec) {
    spec.position = world.Apply(Vec3d(0, 0, 0));
    const Vec3d forward = world.ApplyLinear(Vec3d(0, 0, -1));
    spec.up = world.ApplyLinear(Vec3d(0, 1, 0));
    if (!(Length(Cross(forward, spec.up)) > 0)) return false;
    spec.look_at = spec.position + Normalize(forward);
    return true;
}

std::vector<Affine> SceneAnimation::WorldTransforms(double seconds) const {
    std::vector<Vec3d> translation(nodes.size()), scale(nodes.size());
    std::vector<std::array<double, 4>> rotation(nodes.size());
    for (size_t i = 0; i < nodes.size(); ++i) {
        translation[i] = nodes[i].translation;
        rotation[i] = nodes[i].rotation;
        scale[i] = nodes[i].scale;
    }
    double v[4];
    for (const AnimationChannel& c : channels) {
        const size_t i = size_t(c.node);
        switch (c.path) {
            case AnimationChannel::Path::kTranslation:
                c.keys.At(seconds, std::span(v, 3));
                translation[i] = {v[0], v[1], v[2]};
                break;
            case AnimationChannel::Path::kRotation:
                c.keys.At(seconds, std::span(v, 4));
                rotation[i] = {v[0], v[1], v[2], v[3]};
                break;
            case AnimationChannel::Path::kScale:
                c.keys.At(seconds, std::span(v, 3));
                scale[i] = {v[0], v[1], v[2]};
                break;
            case AnimationChannel::Path::kWeights:
                break;
        }
    }
    std::vector<Affine> world(nodes.size());
    for (size_t i = 0; i < nodes.size(); ++i) {
        const AnimationNode& node = nodes[i];
        const Affine local =
            node.has_matrix ? node.matrix : Affine::FromTrs(translation[i], rotation[i], scale[i]);
        world[i] = local.Then(node.parent < 0 ? node.root : world[size_t(node.parent)]);
    }
    return world;
}

absl::Status SceneAnimation::PoseAt(double seconds, Scene& scene) const {
    const auto at = [&](int node) {
        return absl::StrCat(nodes[size_t(node)].where, " at ", seconds, " s");
    };
    const std::vector<Affine> world = WorldTransforms(seconds);
    for (size_t i = 0; i < world.size(); ++i) {
        if (!world[i].IsFinite()) {
            return absl::InvalidArgumentError(
                absl::StrCat(at(int(i)), ": its world transform overflows double range"));
        }
    }
    std::vector<std::vector<double>> weights(nodes.size());
    for (const AnimationChannel& c : channels) {
        if (c.path == AnimationChannel::Path::kWeights) {
            weights[size_t(c.node)] = c.keys.At(seconds);
        }
    }
    for (const AnimatedMesh& mesh : meshes) {
        if (absl::Status s = PoseMesh(mesh, *this, world, weights, seconds, scene); !s.ok()) {
            return s;
        }
    }
    for (const AnimatedSphere& s : spheres) {
        const Affine& w = world[size_t(s.node)];
        Sphere& sphere = scene.spheres[size_t(s.sphere)];
        sphere.center = w.Apply(s.center);
        sphere.radius = s.radius * std::cbrt(std::abs(w.Determinant()));
        if (!InRange(sphere.center)) {
            return absl::InvalidArgumentError(absl::StrCat(at(s.node), ": sphere \"", sphere.name,
                                                           "\" centre ", Beyond(sphere.center)));
        }
        if (!(sphere.radius > 0 && sphere.radius <= kMaxCoordinate)) {
            return absl::InvalidArgumentError(absl::StrCat(at(s.node), ": sphere \"", sphere.name,
                                                           "\" radius ", sphere.radius,
                                                           " is not in (0, 1e15]"));
        }
    }
    for (const AnimatedLight& light : lights) {
        const Affine& w = world[size_t(light.node)];
        const Vec3d position = w.Apply(Vec3d(0, 0, 0));
        const Vec3d axis = w.ApplyLinear(Vec3d(0, 0, -1));
        if (!InRange(position)) {
            return absl::InvalidArgumentError(
                absl::StrCat(at(light.node), ": its light at ", Beyond(position)));
        }
        if (light.kind != AnimatedLight::Kind::kPoint && !(Length(axis) > 0)) {
            return absl::InvalidArgumentError(
                absl::StrCat(at(light.node), ": its transform flattens the light's axis"));
        }
        switch (light.kind) {
            case AnimatedLight::Kind::kPoint:
                scene.point_lights[size_t(light.index)].position = position;
                break;
            case AnimatedLight::Kind::kSpot:
                scene.spot_lights[size_t(light.index)].position = position;
                scene.spot_lights[size_t(light.index)].direction = Normalize(axis);
                break;
            case AnimatedLight::Kind::kDirectional:
                scene.directional_lights[size_t(light.index)].direction = Normalize(axis);
                break;
        }
    }
    if (camera_node >= 0) {
        if (!PlaceGltfCamera(world[size_t(camera_node)], scene.camera)) {
            return absl::InvalidArgumentError(
                absl::StrCat(at(camera_node), ": its transform flattens the camera's view"));
        }
        if (!InRange(scene.camera.position)) {
            return absl::InvalidArgumentError(
                absl::StrCat(at(camera_node), ": its camera at ", Beyond(scene.camera.position)));
        }
    }
    return absl::OkStatus();
}

std::vector<bool> SceneAnimation::MovingNodes() const {
    std::vector<bool> moving(nodes.size(), false);
    for (const AnimationChannel& c : channels) {
        if (c.path != AnimationChannel::Path::kWeights) moving[size_t(c.node)] = true;
    }
    // Parents come first, so one pass carries motion down the tree.
    for (size_t i = 0; i < nodes.size(); ++i) {
        if (nodes[i].parent >= 0 && moving[size_t(nodes[i].parent)]) moving[i] = true;
    }
    return moving;
}

bool SceneAnimation::Moves() const {
    return (camera_node >= 0 && MovingNodes()[size_t(camera_node)]) ||
           std::any_of(meshes.begin(), meshes.end(),
                       [](const AnimatedMesh& m) { return m.moves; }) ||
           std::any_of(spheres.begin(), spheres.end(),
                       [](const AnimatedSphere& s) { return s.moves; }) ||
           std::any_of(lights.begin(), lights.end(),
                       [](const AnimatedLight& l) { return l.moves; });
}

double SceneAnimation::Start() const {
    double start = 0;
    for (size_t i = 0; i < channels.size(); ++i) {
        start = i == 0 ? channels[i].keys.start() : std::min(start, channels[i].keys.start());
    }
    return start;
}

double SceneAnimation::End() const {
    double end = 0;
    for (size_t i = 0; i < channels.size(); ++i) {
        end = i == 0 ? channels[i].keys.end() : std::max(end, channels[i].keys.end());
    }
    return end;
}

}  // namespace lf
