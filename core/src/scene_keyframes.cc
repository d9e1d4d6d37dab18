// A JSON shape's or camera's keyframed `transform`: a node of the scene's animation with
// translation, rotation and scale channels (lf/core/keyframes.h), so SceneAnimation::PoseAt
// moves it like a glTF node.
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/keyframes.h"
#include "lf/core/scene_animation.h"
#include "scene_parser.h"

namespace lf::scene_internal {
namespace {

// Whether `a` is a rotation (or mirror) times a uniform scale: spheres stay spheres under it.
bool ScalesUniformly(const Affine& a) {
    const Vec3d r[3] = {a.Row(0), a.Row(1), a.Row(2)};
    const double s = LengthSquared(r[0]);
    constexpr double kTolerance = 1e-9;
    for (int i = 0; i < 3; ++i) {
        if (std::abs(LengthSquared(r[i]) - s) > kTolerance * s) return false;
        if (std::abs(Dot(r[i], r[(i + 1) % 3])) > kTolerance * s) return false;
    }
    return true;
}

}  // namespace

SceneParser::PlacedTransform SceneParser::ParseAnyTransform(const Node& n, Scaling scaling,
                                                            const std::string& where) {
    n.RequireObject();
    if (n.Has("keyframes")) return ParseKeyframes(n, scaling, where);
    const Affine transform = ParseTransform(n);
    if (scaling == Scaling::kUniform && !ScalesUniformly(transform)) {
        n.Fail("scales unevenly; a sphere takes a uniform scale only (one number)");
    }
    if (scaling == Scaling::kNone &&
        !(ScalesUniformly(transform) && std::abs(std::abs(transform.Determinant()) - 1) < 1e-9)) {
        n.Fail("scales; a camera's transform may only rotate and translate");
    }
    return {transform, -1};
}

SceneParser::PlacedTransform SceneParser::ParseKeyframes(const Node& n, Scaling scaling,
                                                         const std::string& where) {
    n.ExpectObject({"keyframes", "interpolation"});
    Interpolation interpolation = Interpolation::kLinear;
    if (const std::optional<Node> i = n.Find("interpolation")) {
        interpolation = i->OneOf<Interpolation>(
            "interpolation", {{"LINEAR", Interpolation::kLinear}, {"STEP", Interpolation::kStep}});
    }
    const Node keys_node = n.Get("keyframes");
    const std::vector<Node> keys = keys_node.Elements();
    if (keys.empty()) keys_node.Fail("no keyframes; give at least one");
    // Each part a channel: given by every keyframe or by none.
    constexpr const char* kParts[] = {"translate", "rotate", "scale"};
    std::vector<double> times, values[3];
    AnimationNode node;
    node.where = where;
    for (size_t k = 0; k < keys.size(); ++k) {
        const Node& key = keys[k];
        key.ExpectObject({"time", "translate", "rotate", "scale"});
        const Node time = key.Get("time");
        times.push_back(time.Number());
        if (k > 0 && !(times[k] > times[k - 1])) {
            time.Fail(absl::StrCat(times[k], " s is not after keyframes[", k - 1, "].time (",
                                   times[k - 1], " s): times must increase"));
        }
        for (const char* part : kParts) {
            if (key.Has(part) != keys[0].Has(part)) {
                key.Fail(absl::StrCat(
                    key.Has(part) ? "gives" : "lacks", " \"", part, "\", which keyframes[0] ",
                    key.Has(part) ? "does not" : "gives", ": every keyframe gives the same parts"));
            }
        }
        Vec3d translation(0, 0, 0), scale(1, 1, 1);
        std::array<double, 4> rotation{0, 0, 0, 1};
        if (const std::optional<Node> t = key.Find("translate")) translation = t->Vector();
        if (const std::optional<Node> r = key.Find("rotate")) rotation = ParseRotation(*r);
        if (const std::optional<Node> s = key.Find("scale")) {
            if (scaling == Scaling::kNone) {
                s->Fail("a camera's keyframes may only rotate and translate");
            }
            scale = s->json().is_number() ? Vec3d(1, 1, 1) * s->Coordinate() : s->Vector();
            if (!(scale.x > 0 && scale.y > 0 && scale.z > 0)) {
                s->Fail("must be above 0: a keyframed transform neither flattens nor mirrors");
            }
            if (scaling == Scaling::kUniform && !(scale.x == scale.y && scale.y == scale.z)) {
                s->Fail("scales unevenly; a sphere takes a uniform scale only (one number)");
            }
        }
        values[0].insert(values[0].end(), {translation.x, translation.y, translation.z});
        values[1].insert(values[1].end(), rotation.begin(), rotation.end());
        values[2].insert(values[2].end(), {scale.x, scale.y, scale.z});
        if (k == 0) {
            node.translation = translation;
            node.rotation = rotation;
            node.scale = scale;
        }
    }
    const int index = int(animation_.nodes.size());
    animation_.nodes.push_back(node);
    constexpr AnimationChannel::Path kPaths[] = {AnimationChannel::Path::kTranslation,
                                                 AnimationChannel::Path::kRotation,
                                                 AnimationChannel::Path::kScale};
    for (int p = 0; p < 3; ++p) {
        if (!keys[0].Has(kParts[p])) continue;
        const bool rotation = kPaths[p] == AnimationChannel::Path::kRotation;
        absl::StatusOr<Keyframes> channel = Keyframes::Create(
            interpolation, rotation ? KeyframeKind::kRotation : KeyframeKind::kVector,
            rotation ? 4 : 3, times, values[p], keys_node.path());
        // Everything Create checks was checked above, naming the keyframe.
        if (!channel.ok()) throw LoadError{channel.status()};
        animation_.channels.push_back({index, kPaths[p], *std::move(channel)});
    }
    return {Affine::FromTrs(node.translation, node.rotation, node.scale), index};
}

}  // namespace lf::scene_internal
