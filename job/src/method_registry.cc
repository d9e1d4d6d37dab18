#include "lf/job/method_registry.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "absl/strings/str_cat.h"
#include "lf/core/patch_mesh.h"
#include "lf/job/job_spec.h"

namespace lf {

namespace {

// Indexed by Method.
constexpr std::array<MethodInfo, 6> kMethods = {{
    {Method::kPath, "path", WorkKind::kTiles, std::nullopt, false, true, true, true, true, nullptr},
    {Method::kRadiosity, "radiosity", WorkKind::kRadiosity, std::nullopt, false, false, true, true,
     false, RadiosityRefusal},
    {Method::kWhitted, "whitted", WorkKind::kTiles, std::nullopt, false, true, true, true, true,
     nullptr},
    {Method::kLight, "light", WorkKind::kSplatPasses, SplatPlanKind::kLightPaths, true, false,
     false, false, true, nullptr},
    {Method::kBdpt, "bdpt", WorkKind::kSplatPasses, SplatPlanKind::kCameraAndLight, true, true,
     false, false, true, nullptr},
    {Method::kPpm, "ppm", WorkKind::kSplatPasses, SplatPlanKind::kPhotonPasses, false, true, false,
     false, true, nullptr},
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
