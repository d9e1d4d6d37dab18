// The camera's importance (Camera::We, PdfWe, SampleWi): normalised to 1 over the film and the
// lens, and consistent with GenerateRay, for a pinhole and a thin lens.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "lf/core/camera.h"
#include "lf/core/sampler.h"

namespace lf {
namespace {

constexpr double kPi = std::numbers::pi;

// A 48 x 32 film (not square, so the aspect ratio matters), 50 degrees vertically, looking
// from an off-axis point along a tilted axis.
CameraSpec Spec(bool lens) {
    CameraSpec spec;
    spec.position = {1, 2, -3};
    spec.look_at = {1.5, 1.2, 2};
    spec.up = {0, 1, 0};
    spec.fov_y_deg = 50;
    spec.width = 48;
    spec.height = 32;
    if (lens) {
        spec.aperture_radius = 0.2;
        spec.focus_distance = 4;
    }
    return spec;
}

class CameraImportanceTest : public ::testing::TestWithParam<bool> {};

INSTANTIATE_TEST_SUITE_P(Cameras, CameraImportanceTest, ::testing::Values(false, true),
                         [](const auto& info) {
                             return std::string(info.param ? "ThinLens" : "Pinhole");
                         });

// A point connected to the camera by SampleWi, fed back through GenerateRay at the returned
// raster position and the same lens sample, is on the ray that comes out; its importance and
// densities agree with We and PdfWe of that ray.
TEST_P(CameraImportanceTest, SampleWiRoundTripsThroughGenerateRay) {
    const Vec3d origin(0.5, -0.25, 1);  // render space is world minus this
    const Camera camera(Spec(GetParam()), origin);
    const Vec3 position = Vec3(Vec3d(1, 2, -3) - origin);
    int connected = 0;
    for (int i = 0; i < 4000; ++i) {
        Sampler sampler(7, 0, 0, uint64_t(i));
        const Vec2 a = sampler.Get2D(), b = sampler.Get2D(), u_lens = sampler.Get2D();
        // Points in a box around the view, some behind the camera or off the film.
        const Vec3 ref = position + Vec3(-6 + 12 * a.x, -6 + 12 * a.y, -2 + 12 * b.x);
        const std::optional<Camera::ImportanceSample> s = camera.SampleWi(ref, u_lens);
        if (!s) continue;
        ++connected;
        ASSERT_GE(s->raster.x, 0);
        ASSERT_LT(s->raster.x, camera.width());
        ASSERT_GE(s->raster.y, 0);
        ASSERT_LT(s->raster.y, camera.height());
        const int px = int(s->raster.x), py = int(s->raster.y);
        const Ray ray = camera.GenerateRay(px, py, s->raster.x - px, s->raster.y - py, u_lens);
        EXPECT_LT(Length(ray.o - s->lens_point), 1e-5f);
        EXPECT_LT(Length(ray.d + s->wi), 2e-5f) << "ref " << ref.x << " " << ref.y << " " << ref.z;
        EXPECT_NEAR(Length(ref - s->lens_point), s->distance, 1e-5f * s->distance);
        const float we = camera.We(ray);
        EXPECT_NEAR(we, s->we, 1e-3f * s->we);
        // We = pdf_pos pdf_dir / cos: the film and lens are sampled uniformly.
        const Camera::ImportancePdf pdf = camera.PdfWe(ray);
        const Vec3 forward = Normalize(Vec3(Vec3d(0.5, -0.8, 5)));
        EXPECT_NEAR(pdf.pos * pdf.dir / Dot(ray.d, forward), we, 1e-3f * we);
        // The lens density per solid angle at ref: distance^2 / (cos lens area).
        const float lens_area = GetParam() ? float(kPi * 0.04) : 1.0f;
        EXPECT_NEAR(s->pdf, s->distance * s->distance / (Dot(ray.d, forward) * lens_area),
                    1e-3f * s->pdf);
    }
    EXPECT_GT(connected, 500);
}

// The integral of We cos over directions (and over the lens for a thin lens) is 1, and PdfWe's
// direction density integrates to 1: directions uniform on the sphere, lens points uniform on a
// disk a little larger than the lens (We is 0 beyond it only through Raster's focus mapping,
// so the lens is sampled exactly), Monte Carlo within 5 standard errors.
TEST_P(CameraImportanceTest, ImportanceIntegratesToOne) {
    const bool lens = GetParam();
    const Camera camera(Spec(lens), Vec3d());
    const Vec3 position(1, 2, -3);
    const Vec3 right = Normalize(Cross(Normalize(Vec3(0.5f, -0.8f, 5)), Vec3(0, 1, 0)));
    const Vec3 up = Cross(right, Normalize(Vec3(0.5f, -0.8f, 5)));
    const double lens_area = lens ? kPi * 0.04 : 1;
    constexpr int kSamples = 2'000'000;
    double sum_we = 0, sum_we2 = 0, sum_pdf = 0, sum_pdf2 = 0;
    for (int i = 0; i < kSamples; ++i) {
        Sampler sampler(11, 0, 0, uint64_t(i));
        const Vec2 u = sampler.Get2D(), u_lens = sampler.Get2D();
        const float z = 1 - 2 * u.x;
        const float r = std::sqrt(std::max(0.0f, 1 - z * z));
        const float phi = 2 * float(kPi) * u.y;
        const Vec3 w(r * std::cos(phi), r * std::sin(phi), z);
        Vec3 o = position;
        if (lens) {
            // Uniform on the lens disk by polar coordinates (not GenerateRay's concentric map).
            const float rl = 0.2f * std::sqrt(u_lens.x), pl = 2 * float(kPi) * u_lens.y;
            o += right * (rl * std::cos(pl)) + up * (rl * std::sin(pl));
        }
        const Ray ray{o, w};
        const float cos = Dot(w, Normalize(Vec3(0.5f, -0.8f, 5)));
        const double we = camera.We(ray) * cos * 4 * kPi * lens_area;
        const double pdf = camera.PdfWe(ray).dir * 4 * kPi;
        sum_we += we;
        sum_we2 += we * we;
        sum_pdf += pdf;
        sum_pdf2 += pdf * pdf;
    }
    const double mean_we = sum_we / kSamples, mean_pdf = sum_pdf / kSamples;
    const double se_we = std::sqrt((sum_we2 / kSamples - mean_we * mean_we) / kSamples);
    const double se_pdf = std::sqrt((sum_pdf2 / kSamples - mean_pdf * mean_pdf) / kSamples);
    std::printf("integral of We cos %.5f +- %.5f, of pdf_dir %.5f +- %.5f\n", mean_we, se_we,
                mean_pdf, se_pdf);
    EXPECT_NEAR(mean_we, 1, 5 * se_we);
    EXPECT_NEAR(mean_pdf, 1, 5 * se_pdf);
}

// Rays off the film, or leaving backwards, carry no importance.
TEST_P(CameraImportanceTest, OffFilmRaysHaveNoImportance) {
    const Camera camera(Spec(GetParam()), Vec3d());
    const Vec3 position(1, 2, -3);
    const Vec3 forward = Normalize(Vec3(0.5f, -0.8f, 5));
    EXPECT_EQ(camera.We(Ray{position, -forward}), 0);
    EXPECT_EQ(camera.PdfWe(Ray{position, -forward}).dir, 0);
    const Vec3 right = Normalize(Cross(forward, Vec3(0, 1, 0)));
    // 80 degrees off axis, far beyond the 50 x 73 degree field of view.
    const Vec3 side = Normalize(forward * 0.17f + right * 0.98f);
    EXPECT_EQ(camera.We(Ray{position, side}), 0);
    EXPECT_FALSE(camera.SampleWi(position - forward * 2.0f, {0.3f, 0.6f}));
    EXPECT_GT(camera.We(Ray{position, forward}), 0);
}

}  // namespace
}  // namespace lf
