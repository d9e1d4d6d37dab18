// Surfaces rays pass through: alpha-mask holes (camera, bounce and shadow rays) and the back
// faces of single-sided meshes, except where the material transmits.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <utility>

#include "lf/kernels/embree_scene.h"
#include "lf/kernels/shading.h"
#include "plane_render.h"
#include "render_path.h"
#include "test_scenes.h"

namespace lf {
namespace {

// A quad facing +z at z = 0 spanning [-1, 1]^2; uv (0, 0) top left (x = -1, y = 1), u along +x.
TriangleMesh Quad(int material, double z = 0) {
    TriangleMesh m;
    m.material = material;
    m.positions = {{-1, 1, z}, {-1, -1, z}, {1, -1, z}, {1, 1, z}};
    m.uvs = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

// Material 0: a black quad at z = 0 whose texture's left column is transparent (alpha 0) and
// right column opaque; material 1: an emitter of radiance 1 behind it at z = -1, four times
// larger.
Scene MaskedQuadOverEmitter() {
    Scene scene;
    auto image = std::make_shared<TextureImage>();
    image->width = 2;
    image->height = 1;
    image->channels = 4;
    image->texels8 = {255, 255, 255, 0, 255, 255, 255, 255};
    scene.textures.push_back(image);
    Material mask;
    mask.reflectance = Rgb(0);
    mask.base_color_texture.image = 0;
    mask.base_color_texture.nearest = true;
    mask.alpha_mode = Material::AlphaMode::kMask;
    scene.materials.push_back(mask);
    Material emitter;
    emitter.reflectance = Rgb(0);
    emitter.emission = Rgb(1);
    scene.materials.push_back(emitter);
    scene.meshes.push_back(Quad(0));
    TriangleMesh back = Quad(1, -1);
    for (Vec3d& p : back.positions) p = Vec3d(p.x * 4, p.y * 4, p.z);
    scene.meshes.push_back(back);
    scene.camera = testing::SquareCamera({0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 90, 16);
    return scene;
}

// The camera sees the emitter through the left half and the black quad on the right.
TEST(AlphaMask, CameraRaysPassThroughHoles) {
    const Scene scene = MaskedQuadOverEmitter();
    const RenderOutput out = testing::RenderPath(scene, 4).out;
    for (int y = 0; y < 16; ++y) {
        for (int x = 0; x < 16; ++x) {
            if (x == 7 || x == 8) continue;  // footprints across the texel edge
            const float expected = x < 8 ? 1.0f : 0.0f;
            EXPECT_EQ(out.image.Pixel(x, y).g, expected) << "pixel " << x << "," << y;
        }
    }
}

// Shadow rays and bounce rays: from the emitter up to points above the quad, blocked only by
// its opaque half, in both directions of travel.
TEST(AlphaMask, ShadowAndBounceRaysPassThroughHoles) {
    const Scene scene = MaskedQuadOverEmitter();
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    const Vec3d o = (*es)->origin();
    for (double x : {-0.75, -0.25, 0.25, 0.75}) {
        const bool hole = x < 0;
        const SurfacePoint below{Vec3(Vec3d(x, 0.3, -0.5) - o), Vec3(), Vec3(0, 0, 1)};
        const SurfacePoint above{Vec3(Vec3d(x, 0.3, 1) - o), Vec3(), Vec3(0, 0, -1)};
        EXPECT_EQ((*es)->Occluded(SpawnRayTo(below, above)), !hole) << x;
        EXPECT_EQ((*es)->Occluded(SpawnRayTo(above, below)), !hole) << x;
        const std::optional<SurfaceHit> hit = (*es)->Intersect(SpawnRay(above, Vec3(0, 0, -1)));
        ASSERT_TRUE(hit.has_value()) << x;
        EXPECT_EQ(hit->mesh, hole ? 1 : 0) << x;
    }
}

// Light samples in a masked emitter's holes carry nothing.
TEST(AlphaMask, LightSamplesInHolesEmitNothing) {
    Scene scene = MaskedQuadOverEmitter();
    scene.materials[0].emission = Rgb(3);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    const SurfacePoint left = (*es)->TrianglePoint(0, 0, 0.1f, 0.1f, 0);   // near (-1, 1)
    const SurfacePoint right = (*es)->TrianglePoint(0, 1, 0.1f, 0.8f, 0);  // near (1, 1)
    EXPECT_EQ(EmissionAt(**es, left, Rgb(3)), Rgb(0));
    EXPECT_EQ(EmissionAt(**es, right, Rgb(3)), Rgb(3));
}

// The mean of channel c over an image whose pixels all have the same expectation, and its
// standard error from the pixels' spread.
std::pair<double, double> ImageMean(const Image& image, int c) {
    double sum = 0, sum2 = 0;
    const int n = image.width() * image.height();
    for (int y = 0; y < image.height(); ++y) {
        for (int x = 0; x < image.width(); ++x) {
            const double v = image.Pixel(x, y)[c];
            sum += v;
            sum2 += v * v;
        }
    }
    const double mean = sum / n;
    return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1))};
}

// glTF's BLEND by stochastic transparency: a quad of opacity a emitting red 2 in front of an
// emitter of green 1 renders (2 a, 1 - a, 0), the alpha-blended value, in expectation. (As a
// cut-out at 0.5, which BLEND was before, it rendered (0, 1, 0).)
TEST(AlphaBlend, CameraRaysConvergeToTheBlendedValue) {
    Scene scene = MaskedQuadOverEmitter();
    Material& blend = scene.materials[0];
    blend.base_color_texture = {};
    blend.alpha_mode = Material::AlphaMode::kBlend;
    blend.opacity = 0.3f;
    blend.emission = Rgb(2, 0, 0);
    scene.materials[1].emission = Rgb(0, 1, 0);
    // Inside the front quad only: every pixel has the same expectation.
    scene.camera = testing::SquareCamera({0, 0, 1}, {0, 0, 0}, {0, 1, 0}, 60, 16);
    const RenderOutput out = testing::RenderPath(scene, 64).out;
    const float a = blend.opacity;
    const double expected[3] = {2 * a, 1 - a, 0};
    for (int c = 0; c < 3; ++c) {
        const auto [mean, standard_error] = ImageMean(out.image, c);
        if (c < 2) {
            EXPECT_GT(standard_error, 0) << "stochastic, not a fixed cut-out";
        }
        EXPECT_NEAR(mean, expected[c], 5 * standard_error + 1e-6) << "channel " << c;
    }
}

// Shadow rays blend too: a plane of albedo rho under a directional light of irradiance E,
// through a black blended sheet of opacity a that the camera also looks through, renders
// (1 - a)^2 rho E / pi: the light passes the sheet with probability 1 - a, the view too.
TEST(AlphaBlend, ShadowRaysPassWithProbabilityOneMinusOpacity) {
    const Rgb rho(0.5f);
    Scene scene = testing::PlaneUnderCamera(rho);
    Material sheet;
    sheet.reflectance = Rgb(0);
    sheet.alpha_mode = Material::AlphaMode::kBlend;
    sheet.opacity = 0.4f;
    scene.materials.push_back(sheet);
    TriangleMesh m;
    m.material = 1;
    m.positions = {{-5, 1, -5}, {-5, 1, 5}, {5, 1, 5}, {5, 1, -5}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(m);
    const Rgb irradiance(3.0f, 2.0f, 1.0f);
    scene.directional_lights.push_back({Vec3d(0, -1, 0), irradiance});
    const RenderOutput out = testing::RenderPath(scene, 64).out;
    const double pass = 1 - sheet.opacity;
    for (int c = 0; c < 3; ++c) {
        const double expected = pass * pass * rho[c] * irradiance[c] / std::numbers::pi;
        const auto [mean, standard_error] = ImageMean(out.image, c);
        EXPECT_GT(standard_error, 0);
        EXPECT_NEAR(mean, expected, 5 * standard_error + 1e-6) << "channel " << c;
    }
}

// A light sample on a blended emitter carries its radiance times the opacity: what a ray that
// may pass through it sees on average.
TEST(AlphaBlend, LightSamplesCarryTheOpacity) {
    Scene scene = MaskedQuadOverEmitter();
    scene.materials[0].alpha_mode = Material::AlphaMode::kBlend;
    scene.materials[0].opacity = 0.5f;
    scene.materials[0].emission = Rgb(3);
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    const SurfacePoint left = (*es)->TrianglePoint(0, 0, 0.1f, 0.1f, 0);   // texture alpha 0
    const SurfacePoint right = (*es)->TrianglePoint(0, 1, 0.1f, 0.8f, 0);  // texture alpha 1
    EXPECT_EQ(EmissionAt(**es, left, Rgb(3)), Rgb(0));
    EXPECT_EQ(EmissionAt(**es, right, Rgb(3)), Rgb(1.5f));
}

struct SidedCase {
    bool double_sided;
    Material::Type type;
    float transmission;
    bool hit_from_behind;
};

class SingleSided : public ::testing::TestWithParam<SidedCase> {};

TEST_P(SingleSided, BackFacesAreSkippedUnlessTheMaterialTransmits) {
    const SidedCase c = GetParam();
    Scene scene;
    Material m;
    m.type = c.type;
    m.transmission = c.transmission;
    m.double_sided = c.double_sided;
    scene.materials.push_back(m);
    scene.meshes.push_back(Quad(0));
    auto es = EmbreeScene::Build(scene);
    ASSERT_TRUE(es.ok()) << es.status();
    const Ray front{Vec3(0.1f, 0.2f, 2), Vec3(0, 0, -1)};
    const Ray back{Vec3(0.1f, 0.2f, -2), Vec3(0, 0, 1)};
    EXPECT_TRUE((*es)->Intersect(front).has_value());
    EXPECT_TRUE((*es)->Occluded(Ray{front.o, front.d, 4}));
    EXPECT_EQ((*es)->Intersect(back).has_value(), c.hit_from_behind);
    EXPECT_EQ((*es)->Occluded(Ray{back.o, back.d, 4}), c.hit_from_behind);
}

INSTANTIATE_TEST_SUITE_P(Materials, SingleSided,
                         ::testing::Values(SidedCase{true, Material::Type::kLambert, 0, true},
                                           SidedCase{false, Material::Type::kLambert, 0, false},
                                           SidedCase{false, Material::Type::kPrincipled, 0, false},
                                           SidedCase{false, Material::Type::kPrincipled, 1, true},
                                           SidedCase{false, Material::Type::kDielectric, 0, true}));

// Attribute arrays of the wrong length and textures that do not exist are refused, not read.
TEST(EmbreeSceneInput, BadAttributesAndTextureRefsAreRefused) {
    Scene scene = MaskedQuadOverEmitter();
    scene.source = "bad.gltf";
    scene.meshes[0].name = "leaf";
    scene.meshes[0].normals.assign(3, Vec3(0, 0, 1));
    absl::StatusOr<std::unique_ptr<EmbreeScene>> es = EmbreeScene::Build(scene);
    ASSERT_FALSE(es.ok());
    EXPECT_EQ(es.status().message(), "bad.gltf: mesh 'leaf' has 3 normals for 4 vertices");

    scene.meshes[0].normals.clear();
    scene.materials[0].name = "bark";
    scene.materials[0].base_color_texture.image = 5;
    es = EmbreeScene::Build(scene);
    ASSERT_FALSE(es.ok());
    EXPECT_EQ(es.status().message(), "bad.gltf: material 'bark' uses texture 5 of 1");
}

}  // namespace
}  // namespace lf
