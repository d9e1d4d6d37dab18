#include <optional>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lf/core/pixel_filter.h"
#include "scene_parser.h"

namespace lf::scene_internal {

CameraSpec SceneParser::ParseCamera(const Node& n) {
    n.ExpectObject({"type", "position", "look_at", "up", "fov_y_deg", "half_height", "resolution",
                    "medium", "aperture_radius", "focus_distance", "filter", "transform"});
    CameraSpec camera;
    if (const std::optional<Node> type = n.Find("type")) {
        if (type->String() == "orthographic") {
            camera.projection = CameraSpec::Projection::kOrthographic;
        } else if (type->String() != "perspective") {
            type->Fail(absl::StrCat("unknown camera type \"", type->String(),
                                    "\"; expected perspective or orthographic"));
        }
    }
    const bool orthographic = camera.projection == CameraSpec::Projection::kOrthographic;
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
    if (orthographic) {
        const Node half = n.Get("half_height");
        camera.half_height = half.NumberIn(0, kMaxCoordinate, "above 0 (scene units)");
        if (camera.half_height == 0) half.Fail("must be above 0 (scene units)");
        for (const char* key : {"fov_y_deg", "aperture_radius", "focus_distance"}) {
            if (const std::optional<Node> k = n.Find(key)) {
                k->Fail("has no meaning for an orthographic camera");
            }
        }
    } else {
        if (const std::optional<Node> half = n.Find("half_height")) {
            half->Fail("is for orthographic cameras (\"type\": \"orthographic\")");
        }
        const Node fov = n.Get("fov_y_deg");
        camera.fov_y_deg = fov.Number();
        if (!(camera.fov_y_deg > 0 && camera.fov_y_deg < 180)) {
            fov.Fail(absl::StrCat("must be in (0, 180) degrees, got ", camera.fov_y_deg));
        }
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
    if (const std::optional<Node> filter = n.Find("filter")) camera.filter = ParseFilter(*filter);
    if (const std::optional<Node> transform = n.Find("transform")) {
        const PlacedTransform placed = ParseAnyTransform(*transform, Scaling::kNone, "camera");
        if (placed.node >= 0) {
            // A child node holds the camera as glTF places one (looking down its -Z, +Y up),
            // so PoseAt moves it as it moves a glTF camera.
            const Vec3d f = Normalize(camera.look_at - camera.position);
            const Vec3d r = Normalize(Cross(f, camera.up)), u = Cross(r, f);
            AnimationNode node;
            node.where = "camera";
            node.parent = placed.node;
            node.has_matrix = true;
            for (int i = 0; i < 3; ++i) node.matrix.m[i] = {r[i], u[i], -f[i], camera.position[i]};
            json_camera_node_ = int(animation_.nodes.size());
            animation_.nodes.push_back(node);
        }
        camera.position = placed.rest.Apply(camera.position);
        camera.look_at = placed.rest.Apply(camera.look_at);
        camera.up = placed.rest.ApplyLinear(camera.up);
    }
    return camera;
}

PixelFilter SceneParser::ParseFilter(const Node& n) {
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

}  // namespace lf::scene_internal
