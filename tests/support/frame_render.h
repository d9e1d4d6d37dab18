// Rendering light paths of a frame method (lf/kernels/frame_renderer.h) into an image in
// frame_merge.h's normalisation, for kernel tests: what local mode and the coordinator do,
// without the plan.
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "lf/core/camera.h"
#include "lf/core/image.h"
#include "lf/core/splat_list.h"
#include "lf/job/frame_merge.h"
#include "lf/kernels/embree_scene.h"
#include "lf/kernels/frame_renderer.h"
#include "lf/local/method_factory.h"

namespace lf::testing {

// Light paths of [begin, end) by parity (the halves their splats go to).
inline std::array<uint64_t, 2> PathsByHalf(uint64_t begin, uint64_t end) {
    return {(end + 1) / 2 - (begin + 1) / 2, end / 2 - begin / 2};
}

struct FrameRender {
    Image image;  // R, G, B, A.*, B.*: SetFrameTile of the whole frame
    RenderStats stats;
};

// The image of light paths [begin, end) of `renderer` (no camera part).
inline FrameRender RenderFramePaths(const FrameRenderer& renderer, const Camera& camera,
                                    uint64_t begin, uint64_t end) {
    const PixelRect frame{0, 0, camera.width(), camera.height()};
    TileSums camera_sums(PixelRect{0, 0, 0, 0});
    SplatList splats(camera.width(), camera.height());
    FrameWork work;
    work.path_begin = begin;
    work.path_end = end;
    renderer.Render(work, camera_sums, splats);
    TileSums splat_tile(frame), empty(frame);
    splats.AddTo(splat_tile);
    SplatNormalization norm;
    norm.frame_pixels = uint64_t(camera.width()) * uint64_t(camera.height());
    norm.paths = PathsByHalf(begin, end);
    FrameRender out{Image(camera.width(), camera.height()), camera_sums.stats};
    SetFrameTile(out.image, empty, splat_tile, norm);
    return out;
}

// A frame method's renderer over `scene`, which must build; keeps the scene and camera alive.
struct FrameSetup {
    std::unique_ptr<EmbreeScene> embree;
    std::unique_ptr<Camera> camera;
    std::unique_ptr<FrameRenderer> renderer;
};

inline FrameSetup MakeFrameSetup(const Scene& scene, std::string_view method,
                                 const FrameRenderSettings& settings) {
    FrameSetup s;
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    s.embree = std::move(*es);
    s.camera = std::make_unique<Camera>(scene.camera, s.embree->origin());
    auto r = MakeFrameRenderer(*FindMethod(method), *s.embree, *s.camera, settings);
    EXPECT_TRUE(r.ok()) << r.status();
    s.renderer = std::move(*r);
    return s;
}

}  // namespace lf::testing
