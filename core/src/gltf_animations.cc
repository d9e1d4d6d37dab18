// glTF animations, skins and morph targets into a SceneAnimation (lf/core/scene_animation.h):
// the whole node tree in rest pose, every channel of every animation, and for each node the
// default scene renders, what it drives.
#include <algorithm>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gltf_importer.h"
#include "lf/core/keyframes.h"
#include "lf/core/scene_animation.h"

namespace lf::gltf_internal {
namespace {

std::vector<Vec3d> Vec3s(const std::vector<float>& floats) {
    std::vector<Vec3d> out(floats.size() / 3);
    for (size_t i = 0; i < out.size(); ++i) {
        out[i] = {floats[3 * i], floats[3 * i + 1], floats[3 * i + 2]};
    }
    return out;
}

// A channel's target.path, or none for paths this importer does not animate (an extension's).
std::optional<AnimationChannel::Path> ChannelPath(const std::string& path) {
    if (path == "translation") return AnimationChannel::Path::kTranslation;
    if (path == "rotation") return AnimationChannel::Path::kRotation;
    if (path == "scale") return AnimationChannel::Path::kScale;
    if (path == "weights") return AnimationChannel::Path::kWeights;
    return std::nullopt;
}

int Attribute(const std::map<std::string, int>& attributes, const char* key) {
    const auto found = attributes.find(key);
    return found == attributes.end() ? -1 : found->second;
}

}  // namespace

bool GltfImporter::Animates() const {
    if (!model_.animations.empty() || !model_.skins.empty()) return true;
    return std::any_of(model_.meshes.begin(), model_.meshes.end(), [](const tinygltf::Mesh& m) {
        return std::any_of(m.primitives.begin(), m.primitives.end(),
                           [](const tinygltf::Primitive& p) { return !p.targets.empty(); });
    });
}

void GltfImporter::AnimationStep(const std::function<void()>& step) {
    if (!animating_) return;
    try {
        step();
    } catch (const GltfError& e) {
        animating_ = false;
        Warn(absl::StrCat("animation ignored: ", e.message));
        // The first fault of a scene's files is the one its frames are refused with.
        if (options_.animation_error->ok()) {
            *options_.animation_error =
                absl::InvalidArgumentError(absl::StrCat(name_, ": ", e.message));
        }
    }
}

void GltfImporter::ReadNodeTree() {
    SceneAnimation& animation = *options_.animation;
    const int n = int(model_.nodes.size());
    std::vector<int> parent(size_t(n), -1);
    for (int i = 0; i < n; ++i) {
        for (const int child : model_.nodes[size_t(i)].children) {
            // Out-of-range children and shared ones are the scene traversal's errors.
            if (child >= 0 && child < n && parent[size_t(child)] < 0 && child != i) {
                parent[size_t(child)] = i;
            }
        }
    }
    node_of_.assign(size_t(n), -1);
    // Depth first from the roots, so parents come first; nodes on a cycle are never reached.
    std::vector<int> stack;
    for (int i = n - 1; i >= 0; --i) {
        if (parent[size_t(i)] < 0) stack.push_back(i);
    }
    while (!stack.empty()) {
        const int i = stack.back();
        stack.pop_back();
        if (node_of_[size_t(i)] >= 0) continue;
        const tinygltf::Node& node = model_.nodes[size_t(i)];
        AnimationNode out;
        out.where = absl::StrCat(name_, ": nodes[", i, "]", Quoted(node.name));
        const std::string where = absl::StrCat("nodes[", i, "]", Quoted(node.name));
        const int up = parent[size_t(i)];
        out.parent = up < 0 ? -1 : node_of_[size_t(up)];
        out.root = options_.transform;
        out.matrix = LocalTransform(node, where);
        out.has_matrix = !node.matrix.empty();
        out.translation = NodeTranslation(node);
        out.rotation = NodeRotation(node, where);
        out.scale = NodeScale(node);
        out.weights = node.weights;
        node_of_[size_t(i)] = int(animation.nodes.size());
        animation.nodes.push_back(std::move(out));
        for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) {
            if (*c >= 0 && *c < n && parent[size_t(*c)] == i) stack.push_back(*c);
        }
    }
}

void GltfImporter::ReadAnimations() {
    SceneAnimation& animation = *options_.animation;
    for (size_t a = 0; a < model_.animations.size(); ++a) {
        const tinygltf::Animation& anim = model_.animations[a];
        const std::string at = absl::StrCat("animations[", a, "]", Quoted(anim.name));
        for (size_t c = 0; c < anim.channels.size(); ++c) {
            const tinygltf::AnimationChannel& channel = anim.channels[c];
            const std::string where = absl::StrCat(at, ".channels[", c, "]");
            const std::optional<AnimationChannel::Path> path = ChannelPath(channel.target_path);
            if (!path) {
                Tally(absl::StrCat("target.path \"", channel.target_path,
                                   "\" not supported, channel ignored"),
                      "channel", where);
                continue;
            }
            const AnimationChannel::Path path_kind = *path;
            int width = path_kind == AnimationChannel::Path::kRotation ? 4 : 3;
            if (channel.target_node < 0) {
                // Only extensions target something other than a node.
                Tally("channel without a target node ignored", "channel", where);
                continue;
            }
            if (channel.target_node >= int(model_.nodes.size())) {
                Fail(where, absl::StrCat("target node ", channel.target_node,
                                         " does not exist (the file has ", model_.nodes.size(),
                                         " nodes)"));
            }
            const tinygltf::Node& node = model_.nodes[size_t(channel.target_node)];
            const std::string node_where =
                absl::StrCat("nodes[", channel.target_node, "]", Quoted(node.name));
            const int node_index = node_of_[size_t(channel.target_node)];
            if (node_index < 0) {
                Fail(where, absl::StrCat("target ", node_where, " lies on a cycle of children"));
            }
            if (path_kind != AnimationChannel::Path::kWeights && !node.matrix.empty()) {
                Fail(where, absl::StrCat("target ", node_where,
                                         " has a matrix; channels may only target nodes given "
                                         "by translation, rotation and scale"));
            }
            if (channel.sampler < 0 || channel.sampler >= int(anim.samplers.size())) {
                Fail(where, absl::StrCat("sampler ", channel.sampler, " does not exist (", at,
                                         " has ", anim.samplers.size(), ")"));
            }
            const tinygltf::AnimationSampler& sampler = anim.samplers[size_t(channel.sampler)];
            const std::string sampler_at = absl::StrCat(at, ".samplers[", channel.sampler, "]");
            const absl::StatusOr<Interpolation> interpolation =
                ParseInterpolation(sampler.interpolation, sampler_at);
            if (!interpolation.ok()) throw GltfError{std::string(interpolation.status().message())};
            // Keyframes::Create checks the numbers, naming the key and its time.
            const std::vector<float> input =
                Floats(sampler.input, 1, sampler_at + ".input", /*any_value=*/true);
            std::vector<float> output;
            if (path_kind == AnimationChannel::Path::kWeights) {
                output = Floats(sampler.output, 1, sampler_at + ".output", true);
                const int targets =
                    node.mesh >= 0 && node.mesh < int(model_.meshes.size()) &&
                            !model_.meshes[size_t(node.mesh)].primitives.empty()
                        ? int(model_.meshes[size_t(node.mesh)].primitives[0].targets.size())
                        : 0;
                if (targets == 0) {
                    Fail(where, absl::StrCat("animates the morph weights of ", node_where,
                                             ", whose mesh has no morph targets"));
                }
                width = targets;
            } else {
                output = Floats(sampler.output, width, sampler_at + ".output", true);
            }
            absl::StatusOr<Keyframes> keys = Keyframes::Create(
                *interpolation,
                path_kind == AnimationChannel::Path::kRotation ? KeyframeKind::kRotation
                                                               : KeyframeKind::kVector,
                width, std::vector<double>(input.begin(), input.end()),
                std::vector<double>(output.begin(), output.end()), sampler_at);
            if (!keys.ok()) throw GltfError{std::string(keys.status().message())};
            animation.channels.push_back({node_index, path_kind, std::move(*keys)});
        }
    }
}

GltfImporter::Counts GltfImporter::CountObjects() const {
    return {cameras_.size(), scene_.point_lights.size(), scene_.spot_lights.size(),
            scene_.directional_lights.size()};
}

void GltfImporter::AnimateNode(int index, const Counts& before) {
    SceneAnimation& animation = *options_.animation;
    const int node = node_of_[size_t(index)];
    // A node on a cycle of children is not in the tree; the traversal refuses it next.
    if (node < 0) return;
    if (cameras_.size() > before.cameras) cameras_.back().node = node;
    if (!moving_[size_t(node)]) return;
    const auto light = [&](AnimatedLight::Kind kind, size_t was, size_t now) {
        if (now > was) animation.lights.push_back({kind, int(was), node, true});
    };
    light(AnimatedLight::Kind::kPoint, before.point_lights, scene_.point_lights.size());
    light(AnimatedLight::Kind::kSpot, before.spot_lights, scene_.spot_lights.size());
    light(AnimatedLight::Kind::kDirectional, before.directional_lights,
          scene_.directional_lights.size());
}

void GltfImporter::AnimateMesh(int index, int scene_mesh, int primitive,
                               const std::string& node_where) {
    SceneAnimation& animation = *options_.animation;
    const tinygltf::Node& node = model_.nodes[size_t(index)];
    const tinygltf::Mesh& mesh = model_.meshes[size_t(node.mesh)];
    const tinygltf::Primitive& prim = mesh.primitives[size_t(primitive)];
    const int node_index = node_of_[size_t(index)];
    const bool weights_animated = std::any_of(
        animation.channels.begin(), animation.channels.end(), [&](const AnimationChannel& c) {
            return c.node == node_index && c.path == AnimationChannel::Path::kWeights;
        });
    AnimatedMesh out;
    out.mesh = scene_mesh;
    out.node = node_index;
    out.moves = moving_[size_t(node_index)] || weights_animated;
    if (node.skin < 0 && prim.targets.empty() && !out.moves) return;
    const std::string where =
        absl::StrCat("meshes[", node.mesh, "]", Quoted(mesh.name), ".primitives[", primitive, "]");
    const std::string at = where + ".attributes.";
    out.positions = Vec3s(Floats(Attribute(prim.attributes, "POSITION"), 3, at + "POSITION"));
    const size_t n = out.positions.size();
    if (const int normal = Attribute(prim.attributes, "NORMAL"); normal >= 0) {
        out.normals = Vec3s(Floats(normal, 3, at + "NORMAL"));
    }
    if (const int tangent = Attribute(prim.attributes, "TANGENT"); tangent >= 0) {
        const std::vector<float> t = Floats(tangent, 4, at + "TANGENT");
        out.tangents.resize(n);
        for (size_t i = 0; i < n; ++i) {
            out.tangents[i] = {t[4 * i], t[4 * i + 1], t[4 * i + 2], t[4 * i + 3]};
        }
    }
    for (size_t t = 0; t < prim.targets.size(); ++t) {
        MorphTarget target;
        const std::string target_at = absl::StrCat(where, ".targets[", t, "].");
        const auto deltas = [&](const char* key, std::vector<Vec3d>& into) {
            const int accessor = Attribute(prim.targets[t], key);
            if (accessor < 0) return;
            into = Vec3s(Floats(accessor, 3, target_at + key));
            if (into.size() != n) {
                Fail(target_at + key, absl::StrCat(into.size(), " elements for ", n, " vertices"));
            }
        };
        deltas("POSITION", target.positions);
        if (!out.normals.empty()) deltas("NORMAL", target.normals);
        if (!out.tangents.empty()) deltas("TANGENT", target.tangents);
        out.targets.push_back(std::move(target));
    }
    out.weights.assign(prim.targets.size(), 0.0);
    if (!mesh.weights.empty()) {
        if (mesh.weights.size() != prim.targets.size()) {
            Fail(absl::StrCat("meshes[", node.mesh, "]", Quoted(mesh.name)),
                 absl::StrCat("weights has ", mesh.weights.size(), " numbers for ",
                              prim.targets.size(), " morph targets"));
        }
        out.weights = mesh.weights;
    }
    if (!node.weights.empty() && node.weights.size() != prim.targets.size()) {
        Fail(node_where, absl::StrCat("weights has ", node.weights.size(), " numbers for ",
                                      prim.targets.size(), " morph targets"));
    }
    if (node.skin >= 0) {
        out.skin = Skin(node.skin, node_where);
        const size_t joints = animation.skins[size_t(out.skin)].joints.size();
        const bool second = Attribute(prim.attributes, "JOINTS_1") >= 0 &&
                            Attribute(prim.attributes, "WEIGHTS_1") >= 0;
        out.influences = second ? 8 : 4;
        out.joints.assign(n * size_t(out.influences), 0);
        out.joint_weights.assign(n * size_t(out.influences), 0.0);
        for (int set = 0; set < (second ? 2 : 1); ++set) {
            const std::string joints_key = absl::StrCat("JOINTS_", set);
            const std::string weights_key = absl::StrCat("WEIGHTS_", set);
            const int joints_accessor = Attribute(prim.attributes, joints_key.c_str());
            const int weights_accessor = Attribute(prim.attributes, weights_key.c_str());
            if (joints_accessor < 0 || weights_accessor < 0) {
                Fail(where, absl::StrCat(node_where, " skins it, but it has no ", joints_key,
                                         " and ", weights_key));
            }
            const AccessorData d = Accessor(joints_accessor, at + joints_key);
            if (d.components != 4 || d.count != n ||
                (d.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                 d.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)) {
                Fail(at + joints_key, absl::StrCat("accessors[", joints_accessor, "] must be ", n,
                                                   " VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT"));
            }
            const std::vector<float> w = Floats(weights_accessor, 4, at + weights_key);
            if (w.size() != 4 * n) Fail(at + weights_key, "count differs from POSITION");
            for (size_t v = 0; v < n; ++v) {
                for (int c = 0; c < 4; ++c) {
                    const unsigned char* p = d.data + v * d.stride + size_t(c * d.component_size);
                    uint16_t joint = *p;
                    if (d.component_size == 2) std::memcpy(&joint, p, 2);
                    if (joint >= joints) {
                        Fail(at + joints_key,
                             absl::StrCat("vertex ", v, " names joint ", joint, ", but skins[",
                                          node.skin, "] has ", joints, " joints"));
                    }
                    const size_t k = v * size_t(out.influences) + size_t(set * 4 + c);
                    out.joints[k] = joint;
                    out.joint_weights[k] = w[4 * v + size_t(c)];
                }
            }
        }
        const AnimationSkin& skin = animation.skins[size_t(out.skin)];
        out.moves =
            weights_animated || std::any_of(skin.joints.begin(), skin.joints.end(),
                                            [&](int joint) { return moving_[size_t(joint)]; });
    }
    animation.meshes.push_back(std::move(out));
}

int GltfImporter::Skin(int index, const std::string& node_where) {
    if (index >= int(model_.skins.size())) {
        Fail(node_where, absl::StrCat("skin ", index, " does not exist (the file has ",
                                      model_.skins.size(), ")"));
    }
    if (const auto found = skin_of_.find(index); found != skin_of_.end()) return found->second;
    const tinygltf::Skin& skin = model_.skins[size_t(index)];
    const std::string where = absl::StrCat("skins[", index, "]", Quoted(skin.name));
    AnimationSkin out;
    for (size_t j = 0; j < skin.joints.size(); ++j) {
        const int joint = skin.joints[j];
        if (joint < 0 || joint >= int(model_.nodes.size()) || node_of_[size_t(joint)] < 0) {
            Fail(absl::StrCat(where, ".joints[", j, "]"),
                 absl::StrCat("node ", joint, " does not exist (the file has ", model_.nodes.size(),
                              " nodes)"));
        }
        out.joints.push_back(node_of_[size_t(joint)]);
    }
    out.inverse_bind.resize(skin.joints.size());
    if (skin.inverseBindMatrices >= 0) {
        const std::vector<float> m =
            Floats(skin.inverseBindMatrices, 16, where + ".inverseBindMatrices");
        if (m.size() != 16 * skin.joints.size()) {
            Fail(where + ".inverseBindMatrices",
                 absl::StrCat(m.size() / 16, " matrices for ", skin.joints.size(), " joints"));
        }
        for (size_t j = 0; j < skin.joints.size(); ++j) {
            // Column-major 4x4, its last row 0, 0, 0, 1.
            for (int r = 0; r < 3; ++r) {
                for (int c = 0; c < 4; ++c) out.inverse_bind[j].m[r][c] = m[16 * j + 4 * c + r];
            }
        }
    }
    SceneAnimation& animation = *options_.animation;
    skin_of_[index] = int(animation.skins.size());
    animation.skins.push_back(std::move(out));
    return skin_of_[index];
}

}  // namespace lf::gltf_internal
