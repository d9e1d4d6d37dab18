#include "lf/job/method_registry.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "absl/strings/str_cat.h"
#include "lf/core/patch_mesh.h"
#include "lf/core/sphere_mesh.h"
#include "lf/job/job_spec.h"

namespace lf {

namespace {

// FailedPrecondition for `method` and a scene's media limitation `why`; Ok when `why` is empty.
absl::Status MediaRefusal(Method method, const std::string& why) {
    if (why.empty()) return absl::OkStatus();
    const bool lacks_model = method == Method::kWhitted || method == Method::kRadiosity;
    return absl::FailedPreconditionError(
        absl::StrCat("method ", MethodName(method), ": ", why,
                     lacks_model ? absl::StrCat(", which ", MethodName(method), " does not model")
                                 : absl::StrCat(": not yet supported by ", MethodName(method)),
                     "; use --method path"));
}

// Every method but the path tracer and bdpt renders homogeneous absorbers only.
template <Method kMethod>
absl::Status MediaOnlyRefusal(const Scene& scene) {
    return MediaRefusal(kMethod, MediaLimitation(scene));
}

absl::Status BdptMediaRefusal(const Scene& scene) {
    return MediaRefusal(Method::kBdpt, BdptMediaLimitation(scene));
}

absl::Status RadiosityAndMediaRefusal(const Scene& scene) {
    if (absl::Status s = MediaOnlyRefusal<Method::kRadiosity>(scene); !s.ok()) return s;
    return RadiosityRefusal(scene);
}

// Indexed by Method.
constexpr std::array<MethodInfo, 6> kMethods = {{
    {Method::kPath, "path", WorkKind::kTiles, std::nullopt, false, true, true, true, true, true,
     false, nullptr},
    {Method::kRadiosity, "radiosity", WorkKind::kRadiosity, std::nullopt, false, false, true, true,
     true, false, true, RadiosityAndMediaRefusal},
    {Method::kWhitted, "whitted", WorkKind::kTiles, std::nullopt, false, true, true, false, true,
     true, false, MediaOnlyRefusal<Method::kWhitted>},
    {Method::kLight, "light", WorkKind::kSplatPasses, SplatPlanKind::kLightPaths, true, false,
     false, false, false, true, false, MediaOnlyRefusal<Method::kLight>},
    {Method::kBdpt, "bdpt", WorkKind::kSplatPasses, SplatPlanKind::kCameraAndLight, true, true,
     false, false, false, true, false, BdptMediaRefusal},
    {Method::kPpm, "ppm", WorkKind::kSplatPasses, SplatPlanKind::kPhotonPasses, false, true, false,
     false, false, true, false, MediaOnlyRefusal<Method::kPpm>},
}};

constexpr bool IndexedByMethod() {
    for (size_t i = 0; i < kMethods.size(); ++i) {
        if (size_t(kMethods[i].method) != i) return false;
    }
    return true;
}
static_assert(IndexedByMethod());

}  // namespace

std::span<const MethodInfo> AllMethods() { return kMethods; }

const MethodInfo& Info(Method method) { return kMethods[size_t(method)]; }

const char* MethodName(Method method) { return Info(method).name; }

std::optional<Method> FindMethod(std::string_view name) {
    for (const MethodInfo& info : kMethods) {
        if (name == info.name) return info.method;
    }
    return std::nullopt;
}

absl::StatusOr<Method> ParseMethod(std::string_view name) {
    if (std::optional<Method> method = FindMethod(name)) return *method;
    std::string expected;
    for (const MethodInfo& info : kMethods) {
        absl::StrAppend(&expected, expected.empty() ? "" : ", ", info.name);
    }
    return absl::InvalidArgumentError(
        absl::StrCat("method \"", std::string(name), "\": expected one of ", expected));
}

Method MethodOf(const JobSpec& spec) {
    if (std::optional<Method> method = FindMethod(spec.method)) return *method;
    std::fprintf(stderr, "MethodOf: unchecked job spec with method \"%s\"\n", spec.method.c_str());
    std::abort();
}

void PrepareSceneFor(Method method, Scene& scene) {
    if (Info(method).meshes_spheres) TessellateSpheres(scene);
}

std::string MediaLimitation(const Scene& scene) {
    if (scene.camera_medium >= 0) {
        return absl::StrCat("the camera is in medium \"",
                            scene.media[size_t(scene.camera_medium)].name, "\"");
    }
    for (const Material& m : scene.materials) {
        if (m.type == Material::Type::kInterface) {
            return absl::StrCat("material \"", m.name, "\" is an interface between media");
        }
    }
    for (const Medium& m : scene.media) {
        const std::string what = absl::StrCat("medium \"", m.name, "\"");
        if (m.type == Medium::Type::kGrid) return what + " is a grid (heterogeneous)";
        if (!m.sigma_s.IsBlack()) return what + " scatters light (sigma_s > 0)";
        if (m.IsEmissive()) return what + " emits light";
    }
    return "";
}

std::string BdptMediaLimitation(const Scene& scene) {
    for (const Medium& m : scene.media) {
        if (m.IsEmissive()) return absl::StrCat("medium \"", m.name, "\" emits light");
    }
    return "";
}

absl::Status CheckMethodTakesFilter(Method method, const PixelFilter& filter) {
    if (!Info(method).splats_light_paths || filter.type == PixelFilter::Type::kBox) {
        return absl::OkStatus();
    }
    // Revisit when the kernels splat with the filter's weights over its support.
    return absl::FailedPreconditionError(absl::StrCat(
        "method ", MethodName(method), ": the pixel filter ", DescribePixelFilter(filter),
        " is not supported; light tracing and bdpt splat with the box filter only"));
}

absl::Status CheckMethodTakesScene(Method method, const Scene& scene) {
    if (absl::Status s = CheckMethodTakesFilter(method, scene.camera.filter); !s.ok()) return s;
    if (Info(method).splats_light_paths &&
        scene.camera.projection == CameraSpec::Projection::kOrthographic) {
        return absl::FailedPreconditionError(absl::StrCat(
            "method ", MethodName(method),
            ": orthographic cameras are not supported (light paths cannot reach a camera that "
            "sees along one direction); use path, whitted or ppm"));
    }
    const auto refusal = Info(method).scene_refusal;
    return refusal ? refusal(scene) : absl::OkStatus();
}

}  // namespace lf
