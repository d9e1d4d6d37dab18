// A Lambertian plane y = 0 seen from above, rendered and compared pixel by pixel with a closed
// form for its radiance: the test bed for lights (point, spot, directional).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "lf/core/camera.h"
#include "lf/core/image.h"
#include "lf/core/scene.h"

namespace lf::testing {

inline constexpr int kPlaneImageSize = 16;

// Material 0 of albedo `rho` on a 100 x 100 plane at y = 0 (normal +y), a camera 3 above it
// looking down with a 60 degree field of view: the image covers |x|, |z| <= 1.73.
inline Scene PlaneUnderCamera(const Rgb& rho) {
    Scene scene;
    Material plane;
    plane.reflectance = rho;
    scene.materials.push_back(plane);
    TriangleMesh m;
    const double s = 50;
    m.positions = {{-s, 0, -s}, {-s, 0, s}, {s, 0, s}, {s, 0, -s}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(m);
    scene.camera.position = {0, 3, 0};
    scene.camera.look_at = {0, 0, 0};
    scene.camera.up = {0, 0, 1};
    scene.camera.fov_y_deg = 60;
    scene.camera.width = scene.camera.height = kPlaneImageSize;
    return scene;
}

// Checks every pixel of `image` (rendered from `scene` at `spp` samples per pixel, direct light
// only reaching the camera) against radiance(x) per channel, x the plane point a camera ray
// hits. The expected pixel value is the mean of the radiance over the pixel's footprint,
// integrated on a fine grid; its spread over the footprint is the per-sample standard deviation
// the tolerance comes from (5 standard errors), plus 1e-6 of the image's brightest pixel for
// what the grid's midpoints miss at a footprint's rim. Pixels whose footprint straddles a
// discontinuity of the radiance (a shadow's edge), told by `edge`, are skipped. Returns how
// many pixels were compared.
inline int ExpectPlaneMatches(const Scene& scene, const Image& image, uint64_t spp,
                              const std::function<Rgb(const Vec3d&)>& radiance,
                              const std::function<bool(const Vec3d&, const Vec3d&)>& edge = {}) {
    const Camera camera(scene.camera, Vec3d());
    constexpr int kGrid = 24;
    struct Expected {
        double mean[3], sd[3];
        bool straddles;
    };
    std::vector<Expected> expected;
    double brightest = 0;
    for (int py = 0; py < kPlaneImageSize; ++py) {
        for (int px = 0; px < kPlaneImageSize; ++px) {
            double sum[3] = {}, sum2[3] = {};
            bool straddles = false;
            Vec3d first;
            for (int j = 0; j < kGrid; ++j) {
                for (int i = 0; i < kGrid; ++i) {
                    const Ray r =
                        camera.GenerateRay(px, py, (i + 0.5f) / kGrid, (j + 0.5f) / kGrid);
                    const double t = -double(r.o.y) / r.d.y;
                    const Vec3d x(r.o.x + t * r.d.x, 0, r.o.z + t * r.d.z);
                    if (i == 0 && j == 0) first = x;
                    if (edge && edge(first, x)) straddles = true;
                    const Rgb L = radiance(x);
                    for (int c = 0; c < 3; ++c) {
                        sum[c] += L[c];
                        sum2[c] += double(L[c]) * L[c];
                    }
                }
            }
            Expected e{{}, {}, straddles};
            const double n = kGrid * kGrid;
            for (int c = 0; c < 3; ++c) {
                e.mean[c] = sum[c] / n;
                e.sd[c] = std::sqrt(std::max(0.0, sum2[c] / n - e.mean[c] * e.mean[c]));
                brightest = std::max(brightest, e.mean[c]);
            }
            expected.push_back(e);
        }
    }
    int compared = 0;
    for (int py = 0; py < kPlaneImageSize; ++py) {
        for (int px = 0; px < kPlaneImageSize; ++px) {
            const Expected& e = expected[size_t(py * kPlaneImageSize + px)];
            if (e.straddles) continue;
            ++compared;
            const Rgb got = image.Pixel(px, py);
            for (int c = 0; c < 3; ++c) {
                // Midpoint-rule error is far below the sampling error; 1e-5 covers float rounding.
                const double tol =
                    5 * e.sd[c] / std::sqrt(double(spp)) + 1e-5 * e.mean[c] + 1e-6 * brightest;
                EXPECT_NEAR(got[c], e.mean[c], tol) << "pixel " << px << "," << py << " ch " << c;
            }
        }
    }
    return compared;
}

}  // namespace lf::testing
