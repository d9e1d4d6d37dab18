// Rendering a scene with BDPT (lf/kernels/bdpt.h) into per-pixel half estimates, and comparing
// it with the path tracer block by block, for the kernels' BDPT tests.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bonferroni.h"
#include "lf/core/camera.h"
#include "lf/core/scene_loader.h"
#include "lf/kernels/embree_scene.h"
#include "lf/local/method_factory.h"
#include "render_path.h"

namespace lf::testing {

// A frame of BDPT estimates: per pixel the two half estimates (A: even camera samples and their
// light subpaths, B: odd ones), each its camera mean plus its splat sum x W H / N_h, N_h the
// camera samples of that half over the frame (lf/job/splat_merge.h's normalisation).
struct BdptFrame {
    int width = 0, height = 0;
    std::vector<Rgb> half[2];
    RenderStats stats;
    Rgb Mean(int x, int y) const {
        const size_t i = size_t(y * width + x);
        return (half[0][i] + half[1][i]) * 0.5f;
    }
};

inline BdptFrame RenderBdpt(const Scene& scene, uint64_t spp, int max_depth, uint64_t seed = 7) {
    auto es = EmbreeScene::Build(scene);
    EXPECT_TRUE(es.ok()) << es.status();
    const Camera camera(scene.camera, (*es)->origin());
    SplatRenderSettings settings;
    settings.max_depth = max_depth;
    settings.seed = seed;
    auto renderer = MakeSplatRenderer(Method::kBdpt, **es, camera, settings);
    EXPECT_TRUE(renderer.ok()) << renderer.status();
    const int w = camera.width(), h = camera.height();
    const PixelRect rect{0, 0, w, h};
    TileSums sums(rect);
    SplatList splats(w, h);
    (*renderer)->Render(SplatWork{rect, 0, spp, 0, 0}, sums, splats);
    TileSums splat_tile(rect);
    splats.AddTo(splat_tile);
    BdptFrame frame;
    frame.width = w;
    frame.height = h;
    frame.stats = sums.stats;
    for (int half = 0; half < 2; ++half) {
        // Half h holds the camera samples of parity h: spp / 2 of each pixel.
        const double per_pixel = double(spp / 2);
        frame.half[half].resize(size_t(w * h));
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                const PixelSums& s = splat_tile.at(x, y);
                const Rgb splat(float(s.sum[half][0].Value() / per_pixel),
                                float(s.sum[half][1].Value() / per_pixel),
                                float(s.sum[half][2].Value() / per_pixel));
                frame.half[half][size_t(y * w + x)] = sums.at(x, y).HalfMean(half) + splat;
            }
        }
    }
    return frame;
}

// The mean of the channel average over the frame and its standard error from the per-pixel
// A/B differences (Var of a pixel's mean = E[(A - B)^2] / 4).
struct Mean {
    double value = 0, error = 0;
};
inline Mean SplatMean(const BdptFrame& f) {
    double sum = 0, var = 0;
    const double n = double(f.width) * f.height;
    for (int y = 0; y < f.height; ++y) {
        for (int x = 0; x < f.width; ++x) {
            const size_t i = size_t(y * f.width + x);
            const double a = f.half[0][i].Average(), b = f.half[1][i].Average();
            sum += (a + b) / 2;
            var += (a - b) * (a - b) / 4;
        }
    }
    return {sum / n, std::sqrt(var) / n};
}

// The channel-average means of BDPT and the path tracer over the `block` x `block` pixels from
// (x0, y0), and the standard error of their difference from both methods' A/B halves.
struct BlockMeans {
    double bdpt = 0, path = 0, se = 0;
};
inline BlockMeans CompareBlock(const BdptFrame& bd, const Image& pt, int x0, int y0, int block) {
    BlockMeans m;
    double v1 = 0, v2 = 0;
    for (int y = y0; y < y0 + block; ++y) {
        for (int x = x0; x < x0 + block; ++x) {
            const size_t i = size_t(y * bd.width + x);
            const double a = bd.half[0][i].Average(), b = bd.half[1][i].Average();
            m.bdpt += (a + b) / 2;
            v1 += (a - b) * (a - b) / 4;
            const double pa = pt.Pixel(x, y, "A.").Average(), pb = pt.Pixel(x, y, "B.").Average();
            m.path += (pa + pb) / 2;
            v2 += (pa - pb) * (pa - pb) / 4;
        }
    }
    const double n = double(block) * block;
    m.bdpt /= n;
    m.path /= n;
    m.se = std::sqrt(v1 + v2) / n;
    return m;
}

// Compares BDPT with the path tracer block by block (blocks of side `block`, channel
// average): z from the A/B half variances of both; every |z| below the Bonferroni threshold.
// Returns the largest |z|.
inline double CompareWithPathTracer(const std::string& name, const Scene& scene, uint64_t bdpt_spp,
                                    uint64_t path_spp, int max_depth, int block = 8) {
    const BdptFrame bd = RenderBdpt(scene, bdpt_spp, max_depth);
    const RenderOutput pt = testing::RenderPath(scene, path_spp, max_depth, 3).out;
    const int bw = bd.width / block, bh = bd.height / block;
    const double threshold = BonferroniZ(bw * bh);
    double worst = 0;
    for (int by = 0; by < bh; ++by) {
        for (int bx = 0; bx < bw; ++bx) {
            const BlockMeans m = CompareBlock(bd, pt.image, bx * block, by * block, block);
            const double z = m.se > 0 ? (m.bdpt - m.path) / m.se : (m.bdpt == m.path ? 0 : 1e9);
            worst = std::max(worst, std::abs(z));
            EXPECT_LT(std::abs(z), threshold) << name << ": block " << bx << ", " << by << ": bdpt "
                                              << m.bdpt << ", path " << m.path << " +- " << m.se;
        }
    }
    std::printf("[bdpt] %s: %d blocks, largest |z| %.2f (threshold %.2f)\n", name.c_str(), bw * bh,
                worst, threshold);
    return worst;
}

// A scene of tests/scenes at `size` x `size` pixels.
inline Scene LoadSmall(const std::string& file, int size) {
    SceneOptions options;
    options.width = options.height = size;
    absl::StatusOr<Scene> scene = LoadScene(std::string(LF_TEST_SCENES) + "/" + file, options);
    EXPECT_TRUE(scene.ok()) << scene.status();
    return *scene;
}

}  // namespace lf::testing
