// A farm scene reads only the files uploaded with it, by the name its JSON writes: `../` and
// absolute names are keys like any other and load the same scene (same content hash) as
// `render` does from disk, while a name that was not uploaded is refused with one message that
// says nothing of this machine's files.
#include "lf/job/scene_files.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "gltf_files.h"
#include "image_files.h"
#include "lf/core/scene_loader.h"
#include "lf/job/digest.h"
#include "test_dir.h"
#include "vdb_files.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

constexpr char kTriangle[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
constexpr char kOtherTriangle[] = "v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n";

std::string SceneNaming(const std::vector<std::string>& files) {
    std::string shapes;
    for (const std::string& f : files) {
        shapes += std::string(shapes.empty() ? "" : ", ") +
                  R"({"type": "mesh", "material": "lamp", "file": ")" + f + "\"}";
    }
    return R"({"camera": {"position": [0, 0, -1], "look_at": [0, 0, 0], "fov_y_deg": 40, )"
           R"("resolution": [4, 4]}, "materials": {"lamp": {"type": "lambert", )"
           R"("reflectance": [0.5, 0.5, 0.5], "emission": [1, 1, 1]}}, "shapes": [)" +
           shapes + "]}";
}

class SceneFilesTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_scene_files");
        fs::create_directories(dir_ / "scenes");
        fs::create_directories(dir_ / "meshes");
        fs::create_directories(dir_ / "blobs");
    }
    void TearDown() override { fs::remove_all(dir_); }

    // Stores `bytes` as a blob named by its hash and returns its reference under `name`.
    BlobRef Put(const std::string& name, const std::string& bytes) {
        const std::string hash = Sha256Hex(bytes);
        std::ofstream(dir_ / "blobs" / hash, std::ios::binary) << bytes;
        return {name, hash, bytes.size()};
    }
    absl::StatusOr<Scene> Load(const BlobRef& scene, const std::vector<BlobRef>& files) {
        return LoadSceneFromBlobs(scene, files, [&](const std::string& hash) {
            return (dir_ / "blobs" / hash).string();
        });
    }

    fs::path dir_;
};

TEST_F(SceneFilesTest, ParentAndAbsoluteNamesLoadTheSceneRenderLoads) {
    std::ofstream(dir_ / "meshes" / "up.obj") << kTriangle;
    std::ofstream(dir_ / "abs.obj") << kOtherTriangle;
    const std::string absolute = (dir_ / "abs.obj").string();
    const std::string json = SceneNaming({"../meshes/up.obj", absolute});
    std::ofstream(dir_ / "scenes" / "s.json") << json;

    const absl::StatusOr<Scene> local = LoadScene((dir_ / "scenes" / "s.json").string());
    ASSERT_TRUE(local.ok()) << local.status();
    const absl::StatusOr<Scene> farm = Load(
        Put("s.json", json), {Put("../meshes/up.obj", kTriangle), Put(absolute, kOtherTriangle)});
    ASSERT_TRUE(farm.ok()) << farm.status();
    EXPECT_EQ(farm->content_hash, local->content_hash);
    ASSERT_EQ(farm->meshes.size(), 2u);
    EXPECT_EQ(farm->meshes[1].positions, local->meshes[1].positions);
}

TEST_F(SceneFilesTest, NameNotUploadedIsRefusedWithoutSayingWhatExistsHere) {
    // /etc/hostname exists on the machine loading the scene, the other path does not: the two
    // refusals must read alike, name only the scene's own words, and leak no content.
    std::string messages[2];
    const std::string names[2] = {"/etc/hostname", "/no/such/dir/x.obj"};
    for (int i = 0; i < 2; ++i) {
        const absl::StatusOr<Scene> forged =
            Load(Put("scene.json", SceneNaming({"up.obj", names[i]})), {Put("up.obj", kTriangle)});
        ASSERT_FALSE(forged.ok());
        EXPECT_EQ(forged.status().code(), absl::StatusCode::kNotFound);
        messages[i] = std::string(forged.status().message());
        EXPECT_EQ(messages[i], "scene.json: shapes[1].file \"" + names[i] +
                                   "\": not among the files uploaded with the scene");
        EXPECT_EQ(messages[i].find(dir_.string()), std::string::npos) << messages[i];
    }
    // A relative escape, too: resolved by name only, never against any folder.
    const absl::StatusOr<Scene> escape =
        Load(Put("scene.json", SceneNaming({"../../../../../../etc/passwd"})),
             {Put("up.obj", kTriangle)});
    EXPECT_EQ(escape.status().code(), absl::StatusCode::kNotFound) << escape.status();
}

TEST_F(SceneFilesTest, UnreadableBlobErrorNamesTheUploadNotTheBlobFile) {
    BlobRef mesh = Put("up.obj", kTriangle);
    fs::remove(dir_ / "blobs" / mesh.hash);
    const absl::StatusOr<Scene> scene = Load(Put("scene.json", SceneNaming({"up.obj"})), {mesh});
    ASSERT_FALSE(scene.ok());
    EXPECT_NE(scene.status().message().find("up.obj"), std::string::npos) << scene.status();
    EXPECT_EQ(scene.status().message().find(dir_.string()), std::string::npos) << scene.status();
}

TEST_F(SceneFilesTest, OneNameWithTwoContentsIsRefused) {
    const absl::StatusOr<Scene> scene =
        Load(Put("scene.json", SceneNaming({"up.obj"})),
             {Put("up.obj", kTriangle), Put("up.obj", kOtherTriangle)});
    EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
}

TEST_F(SceneFilesTest, LoadingStopsOnceCancelled) {
    std::atomic<bool> cancel{true};
    const absl::StatusOr<Scene> scene = LoadSceneFromBlobs(
        Put("scene.json", SceneNaming({"up.obj"})), {Put("up.obj", kTriangle)},
        [&](const std::string& hash) { return (dir_ / "blobs" / hash).string(); }, &cancel);
    EXPECT_TRUE(absl::IsCancelled(scene.status())) << scene.status();
}

TEST_F(SceneFilesTest, NamesAreKeysWithoutControlCharacters) {
    EXPECT_TRUE(CheckScenePath("../x.obj").ok());
    EXPECT_TRUE(CheckScenePath("/abs/x.obj").ok());
    EXPECT_FALSE(CheckScenePath("").ok());
    EXPECT_FALSE(CheckScenePath("a\nb.obj").ok());
    EXPECT_FALSE(CheckScenePath(std::string(kMaxScenePathBytes + 1, 'a')).ok());
}

// A glTF scene blob keeps its name's extension, which is what makes it load as glTF: .glb and
// .gltf (with its buffer and image uploaded by the names the glTF writes) load the scene render
// loads, a camera and resolution chosen as render would, and a bad one is refused with the
// message render gives.
TEST_F(SceneFilesTest, GltfAndGlbBlobsLoadAsRenderLoadsThem) {
    testing::GltfBuilder b = testing::TexturedTestScene();
    const std::string png = testing::PngBytes(2, 2, 4, testing::TestTexels());
    std::ofstream(dir_ / "scenes" / "s.gltf") << b.Gltf("s.bin");
    std::ofstream(dir_ / "scenes" / "s.bin", std::ios::binary) << b.bin();
    std::ofstream(dir_ / "scenes" / "tex.png", std::ios::binary) << png;
    const SceneOptions options{.camera = "Front", .width = 20, .height = 10};
    const absl::StatusOr<Scene> local = LoadScene((dir_ / "scenes" / "s.gltf").string(), options);
    ASSERT_TRUE(local.ok()) << local.status();
    const std::vector<BlobRef> files = {Put("s.bin", b.bin()), Put("tex.png", png)};
    const auto blob_file = [&](const std::string& hash) {
        return (dir_ / "blobs" / hash).string();
    };
    const absl::StatusOr<Scene> farm =
        LoadSceneFromBlobs(Put("s.gltf", b.Gltf("s.bin")), files, blob_file, nullptr, options);
    ASSERT_TRUE(farm.ok()) << farm.status();
    EXPECT_EQ(farm->content_hash, local->content_hash);
    EXPECT_EQ(farm->camera.width, 20);
    EXPECT_EQ(farm->textures.size(), 1u);
    const absl::StatusOr<Scene> glb =
        LoadSceneFromBlobs(Put("s.glb", b.Glb()), files, blob_file, nullptr, options);
    ASSERT_TRUE(glb.ok()) << glb.status();
    EXPECT_EQ(glb->meshes[0].positions, local->meshes[0].positions);

    b.json()["meshes"][0]["primitives"][0]["mode"] = 0;
    const absl::StatusOr<Scene> bad_local =
        ParseScene(b.Gltf("s.bin"), "s.gltf", ReadBeside((dir_ / "scenes").string()));
    const absl::StatusOr<Scene> bad_farm =
        LoadSceneFromBlobs(Put("s.gltf", b.Gltf("s.bin")), files, blob_file);
    ASSERT_FALSE(bad_farm.ok());
    EXPECT_EQ(bad_farm.status().message(), bad_local.status().message());
    EXPECT_NE(bad_farm.status().message().find("s.gltf: meshes[0] \"quad\".primitives[0]: mode 0"),
              std::string::npos)
        << bad_farm.status();
    // Only what was uploaded: the image, named as the glTF names it, is not here.
    const absl::StatusOr<Scene> no_image = LoadSceneFromBlobs(
        Put("s.glb", testing::TexturedTestScene().Glb()), {Put("s.bin", b.bin())}, blob_file);
    ASSERT_FALSE(no_image.ok());
    EXPECT_NE(no_image.status().message().find("uri \"tex.png\": not among the files uploaded"),
              std::string::npos)
        << no_image.status();
}

// An environment light's sky file is a scene file like a mesh: uploaded by the name the JSON
// writes, loaded from that blob on the farm, and refused by its JSON path when not uploaded.
TEST_F(SceneFilesTest, SkyFileLoadsFromItsBlob) {
    const std::string sky = testing::HdrBytes(2, 1, {1, 1, 1, 0.5f, 0.5f, 0.5f});
    std::ofstream(dir_ / "scenes" / "sky.hdr", std::ios::binary) << sky;
    std::ofstream(dir_ / "scenes" / "up.obj") << kTriangle;
    std::string json = SceneNaming({"up.obj"});
    json.insert(json.size() - 1, R"(, "lights": [{"type": "environment", "file": "sky.hdr"}])");
    std::ofstream(dir_ / "scenes" / "s.json") << json;
    const absl::StatusOr<Scene> local = LoadScene((dir_ / "scenes" / "s.json").string());
    ASSERT_TRUE(local.ok()) << local.status();
    const absl::StatusOr<Scene> farm =
        Load(Put("s.json", json), {Put("up.obj", kTriangle), Put("sky.hdr", sky)});
    ASSERT_TRUE(farm.ok()) << farm.status();
    EXPECT_EQ(farm->content_hash, local->content_hash);
    ASSERT_TRUE(farm->environment && farm->environment->map);
    EXPECT_EQ(farm->environment->map->width, 2);
    const absl::StatusOr<Scene> missing = Load(Put("s.json", json), {Put("up.obj", kTriangle)});
    EXPECT_EQ(missing.status().message(),
              "s.json: lights[0].file \"sky.hdr\": not among the files uploaded with the scene");
}

// A grid medium's .vdb is a file of the scene like a mesh: `submit` uploads what the loader
// reads, and the farm's loader finds it among the uploads or names the JSON field that wants it.
TEST_F(SceneFilesTest, GridMediumFileTravelsAsABlob) {
    const std::string json =
        R"({"camera": {"position": [0, 0, -1], "look_at": [0, 0, 0], "fov_y_deg": 40,
                       "resolution": [4, 4]},
            "materials": {"lamp": {"type": "lambert", "reflectance": [0, 0, 0],
                                   "emission": [1, 1, 1]}},
            "media": {"smoke": {"type": "grid", "file": "cache/smoke.vdb",
                                "sigma_s": [1, 1, 1]}},
            "shapes": [{"type": "mesh", "material": "lamp", "file": "up.obj",
                        "exterior": "smoke"}]})";
    const std::string vdb = testing::VdbBytes({testing::ConstantGrid("density", 0.5f, 3)});
    fs::create_directories(dir_ / "scenes" / "cache");
    std::ofstream(dir_ / "scenes" / "cache" / "smoke.vdb", std::ios::binary) << vdb;
    std::ofstream(dir_ / "scenes" / "up.obj") << kTriangle;

    // What submit uploads: every file the loader reads, by the name it asks for.
    std::map<std::string, std::string> read;
    const SceneFileReader beside = ReadBeside((dir_ / "scenes").string());
    const absl::StatusOr<Scene> local =
        ParseScene(json, "scene.json", [&](const std::string& name) {
            absl::StatusOr<std::string> bytes = beside(name);
            if (bytes.ok()) read[name] = *bytes;
            return bytes;
        });
    ASSERT_TRUE(local.ok()) << local.status();
    ASSERT_EQ(read.count("cache/smoke.vdb"), 1u);

    const absl::StatusOr<Scene> farm =
        Load(Put("scene.json", json), {Put("up.obj", kTriangle), Put("cache/smoke.vdb", vdb)});
    ASSERT_TRUE(farm.ok()) << farm.status();
    EXPECT_EQ(farm->content_hash, local->content_hash);
    ASSERT_EQ(farm->media.size(), 1u);
    EXPECT_EQ(farm->media[0].density->At(1, 1, 1), 0.5f);

    const absl::StatusOr<Scene> missing = Load(Put("scene.json", json), {Put("up.obj", kTriangle)});
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.status().code(), absl::StatusCode::kNotFound);
    EXPECT_EQ(missing.status().message(),
              "scene.json: media.smoke.file \"cache/smoke.vdb\": not among the files uploaded "
              "with the scene");
}

}  // namespace
}  // namespace lf
