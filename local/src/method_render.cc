#include "lf/local/method_render.h"

#include "lf/local/method_factory.h"

namespace lf {

absl::StatusOr<RenderOutput> RenderWithMethod(Method method, const EmbreeScene& scene,
                                              const Camera& camera,
                                              const MethodRenderSettings& settings, uint64_t spp) {
    RenderSettings render;
    render.spp = spp;
    render.seed = settings.seed;
    render.threads = settings.threads;
    render.tile = settings.tile;
    render.clamp = settings.clamp;
    render.sampler = settings.sampler;
    render.light_strategy = settings.light_strategy;
    if (Info(method).work == WorkKind::kTiles) {
        absl::StatusOr<std::unique_ptr<RadianceEstimator>> tracer =
            MakeRayTracer(method, scene, settings.max_depth, settings.light_strategy);
        if (!tracer.ok()) return tracer.status();
        return RenderImage(camera, **tracer, render);
    }
    absl::StatusOr<SplatPlanSettings> plan = SplatPlanSettingsOf(
        MethodName(method), {camera.width(), camera.height(), spp, render.tile, render.passes});
    if (!plan.ok()) return plan.status();
    absl::StatusOr<std::unique_ptr<SplatRenderer>> renderer =
        MakeSplatRenderer(method, scene, camera,
                          SplatRenderSettingsOf<SplatRenderSettings>(
                              settings.max_depth, settings.seed, settings.sampler, settings.clamp,
                              settings.light_strategy, settings.ppm));
    if (!renderer.ok()) return renderer.status();
    return RenderSplatImage(camera, **renderer, *plan, render);
}

}  // namespace lf
