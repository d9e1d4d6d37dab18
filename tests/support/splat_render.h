// Rendering light paths of a splatting method (lf/kernels/splat_renderer.h) into an image in
// splat_merge.h's normalisation, for kernel tests: what local mode and the coordinator do,
// without the plan.
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "lf/core/camera.h"
#include "lf/core/image.h"
#include "lf/core/splat_list.h"
#include "lf/job/splat_merge.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/splat_renderer.h"
#include "lf/local/method_factory.h"

namespace lf::testing {

// Light paths of [begin, end) by parity (the halves their splats go to).
inline std::array<uint64_t, 2> PathsByHalf(uint64_t begin, uint64_t end) {
    return {(end + 1) / 2 - (begin + 1) / 2, end / 2 - begin / 2};
}

struct SplatRender {
    Image image;  // R, G, B, A.*, B.*: SetSplatTile of the whole frame
    RenderStats stats;
};

// The image of light paths [begin, end) of `renderer` (no camera part).
inline SplatRender RenderSplatPaths(const SplatRenderer& renderer, const Camera& camera,
                                    uint64_t begin, uint64_t end) {
    const PixelRect frame{0, 0, camera.width(), camera.height()};
    TileSums camera_sums(PixelRect{0, 0, 0, 0});
    SplatList splats(camera.width(), camera.height());
    SplatWork work;
    work.path_begin = begin;
    work.path_end = end;
    renderer.Render(work, camera_sums, splats);
    TileSums splat_tile(frame), empty(frame);
    splats.AddTo(splat_tile);
    SplatNormalization norm;
    norm.frame_pixels = uint64_t(camera.width()) * uint64_t(camera.height());
    norm.paths = PathsByHalf(begin, end);
    SplatRender out{Image(camera.width(), camera.height()), camera_sums.stats};
    SetSplatTile(out.image, empty, splat_tile, norm);
    return out;
}

// A splatting method's renderer over `scene`, which must build; keeps the scene and camera alive.
struct SplatSetup {
    std::unique_ptr<EmbreeScene> embree;
    std::unique_ptr<Camera> camera;
    std::unique_ptr<SplatRenderer> renderer;
};

inline SplatSetup MakeSplatSetup(const Scene& scene, std::string_view method,
                                 const SplatRenderSettings& settings) {
    SplatSetup s;
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    s.embree = std::move(*es);
    s.camera = std::make_unique<Camera>(scene.camera, s.embree->origin());
    auto r = MakeSplatRenderer(*FindMethod(method), *s.embree, *s.camera, settings);
    EXPECT_TRUE(r.ok()) << r.status();
    s.renderer = std::move(*r);
    return s;
}

}  // namespace lf::testing
