// Scenes built in code for kernel tests, and statistics helpers for their tolerances.
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "lf/core/image.h"
#include "lf/core/scene.h"

namespace lf::testing {

// A quad of material `material` with corners a, b, c, d (two triangles, one light where it
// emits); its front normal is normalize((b - a) x (c - a)).
inline void AddQuad(Scene& scene, int material, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                    const Vec3d& d) {
    TriangleMesh m;
    m.material = material;
    m.is_quad = true;
    m.positions = {a, b, c, d};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(m);
}

// A square image of `size` pixels from `position` towards `look_at`.
inline CameraSpec SquareCamera(const Vec3d& position, const Vec3d& look_at, const Vec3d& up,
                               double fov_y_deg, int size) {
    CameraSpec camera;
    camera.position = position;
    camera.look_at = look_at;
    camera.up = up;
    camera.fov_y_deg = fov_y_deg;
    camera.width = camera.height = size;
    return camera;
}

// A closed axis-aligned box, all six faces facing inward, every face of material 0.
inline void AddInwardBox(Scene& scene, const Vec3d& center, double half, int material) {
    const double h = half;
    auto quad = [&](Vec3d a, Vec3d b, Vec3d c, Vec3d d) {
        TriangleMesh m;
        m.material = material;
        m.is_quad = true;
        m.positions = {center + a, center + d, center + c, center + b};
        m.triangles = {{0, 1, 2}, {0, 2, 3}};
        scene.meshes.push_back(m);
    };
    // The corners below run outward-facing; listing them reversed makes the normals point in.
    quad({-h, -h, -h}, {h, -h, -h}, {h, -h, h}, {-h, -h, h});  // floor, normal +y
    quad({-h, h, -h}, {-h, h, h}, {h, h, h}, {h, h, -h});      // ceiling, normal -y
    quad({-h, -h, -h}, {-h, -h, h}, {-h, h, h}, {-h, h, -h});  // x = -h, normal +x
    quad({h, -h, -h}, {h, h, -h}, {h, h, h}, {h, -h, h});      // x = +h, normal -x
    quad({-h, -h, -h}, {-h, h, -h}, {h, h, -h}, {h, -h, -h});  // z = -h, normal +z
    quad({-h, -h, h}, {h, -h, h}, {h, h, h}, {-h, h, h});      // z = +h, normal -z
}

// A furnace: a closed box of emission le and lambert reflectance rho, camera inside.
inline Scene MakeFurnace(double half, const Vec3d& center, float rho, float le, int resolution) {
    Scene scene;
    Material m;
    m.name = "furnace";
    m.reflectance = Rgb(rho);
    m.emission = Rgb(le);
    scene.materials.push_back(m);
    AddInwardBox(scene, center, half, 0);
    scene.camera = SquareCamera(center + Vec3d(0.1, -0.2, 0.05) * half,
                                center + Vec3d(1, 0.3, 0.7) * half, {0, 1, 0}, 90, resolution);
    return scene;
}

struct MeanAndError {
    double mean = 0;
    double standard_error = 0;
};

// Mean of a channel over the image, and its standard error from the spread of the pixels
// (each pixel an independent estimate with the same expectation).
inline MeanAndError ChannelMean(const Image& image, const std::string& channel) {
    const std::vector<float>& v = *image.FindChannel(channel);
    double sum = 0, sum2 = 0;
    for (float x : v) {
        sum += x;
        sum2 += double(x) * x;
    }
    const double n = double(v.size());
    const double mean = sum / n;
    const double var = std::max(0.0, (sum2 - n * mean * mean) / (n - 1));
    return {mean, std::sqrt(var / n)};
}

// Per block of block x block pixels (the image's sides multiples of it): the mean of `channel`
// and the variance of that mean, from the half-sample buffers A.channel and B.channel
// (E[(A - B)^2] / 4 is the variance of the pixel mean (A + B) / 2).
inline std::vector<std::pair<double, double>> BlockStatistics(const Image& image,
                                                              const std::string& channel,
                                                              int block) {
    const std::vector<float>& m = *image.FindChannel(channel);
    const std::vector<float>& a = *image.FindChannel("A." + channel);
    const std::vector<float>& b = *image.FindChannel("B." + channel);
    const double n = double(block) * block;
    std::vector<std::pair<double, double>> blocks;
    for (int by = 0; by < image.height(); by += block) {
        for (int bx = 0; bx < image.width(); bx += block) {
            double sum = 0, var = 0;
            for (int y = by; y < by + block; ++y) {
                for (int x = bx; x < bx + block; ++x) {
                    const size_t i = size_t(y) * image.width() + x;
                    sum += m[i];
                    var += (double(a[i]) - b[i]) * (double(a[i]) - b[i]) / 4;
                }
            }
            blocks.push_back({sum / n, var / (n * n)});
        }
    }
    return blocks;
}

}  // namespace lf::testing
