#include "lf/kernels/frame_renderer.h"

#include <string>

#include "absl/strings/str_cat.h"
#include "lf/core/pixel_filter.h"
#include "lf/kernels/bdpt.h"
#include "lf/kernels/light_tracer.h"
#include "lf/kernels/ppm.h"

namespace lf {

bool IsFrameMethod(std::string_view method) {
    return method == "light" || method == "bdpt" || method == "ppm";
}

absl::StatusOr<std::unique_ptr<FrameRenderer>> MakeFrameRenderer(
    std::string_view method, const EmbreeScene& scene, const Camera& camera,
    const FrameRenderSettings& settings) {
    if (method == "light") {
        // A splat lands in the one pixel that holds its raster position: the box filter's
        // footprint. Other filters would need the filter's weights over their support.
        if (camera.filter().type != PixelFilter::Type::kBox) {
            return absl::FailedPreconditionError(absl::StrCat(
                "method light: the pixel filter ", DescribePixelFilter(camera.filter()),
                " is not supported; light tracing splats with the box filter only"));
        }
        return std::make_unique<LightTracer>(scene, camera, settings);
    }
    if (method == "ppm") {
        // Photons are gathered at camera samples placed by filter importance sampling, as the
        // path tracer's: every pixel filter works.
        absl::StatusOr<std::unique_ptr<PpmRenderer>> ppm =
            PpmRenderer::Create(scene, camera, settings);
        if (!ppm.ok()) return ppm.status();
        return std::unique_ptr<FrameRenderer>(std::move(*ppm));
    }
    if (method == "bdpt") {
        absl::StatusOr<std::unique_ptr<BdptRenderer>> bdpt =
            BdptRenderer::Make(scene, camera, settings);
        if (!bdpt.ok()) return bdpt.status();
        return std::unique_ptr<FrameRenderer>(std::move(*bdpt));
    }
    return absl::InvalidArgumentError(absl::StrCat(
        "method ", std::string(method), ": no frame renderer (frame methods: light, bdpt, ppm)"));
}

}  // namespace lf
