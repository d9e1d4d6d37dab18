// A submission reaches only the files uploaded with it: a forged scene naming a file of the
// server's own disk is refused with a message naming the scene's field and nothing of the
// server (its data directory, whether the file exists, or what it holds).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "lf/job/digest.h"
#include "lf/job/settings.h"
#include "lf/server/farm.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

std::string ForgedScene(const std::string& file) {
    return R"({"camera": {"position": [0, 0, -1], "look_at": [0, 0, 0], "fov_y_deg": 40, )"
           R"("resolution": [4, 4]}, "materials": {"lamp": {"type": "lambert", )"
           R"("reflectance": [0.5, 0.5, 0.5], "emission": [1, 1, 1]}}, "shapes": [)"
           R"({"type": "mesh", "material": "lamp", "file": ")" +
           file + "\"}]}";
}

// Uploads `json` alone as scene.json, unless stored already, and submits it for `method`.
absl::StatusOr<std::string> SubmitScene(Farm& farm, const std::string& json,
                                        const std::string& method = defaults::kMethod) {
    JobSpec spec;
    spec.method = method;
    spec.scene = {"scene.json", Sha256Hex(json), json.size()};
    auto upload = farm.StartUpload(spec.scene.hash, json.size());
    if (upload.ok()) {
        if (absl::Status s = (*upload)->Append(json); !s.ok()) return s;
        if (absl::Status s = (*upload)->Finish(); !s.ok()) return s;
    } else if (!absl::IsAlreadyExists(upload.status())) {
        return upload.status();
    }
    return farm.Submit(spec);
}

// A farm whose data directory is in a fresh folder, dir_.
class SceneAccessTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = testing::FreshTestDir("lf_access");
        FarmOptions options;
        options.data_dir = (dir_ / "data").string();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = *std::move(farm);
    }
    void TearDown() override {
        farm_.reset();
        fs::remove_all(dir_);
    }

    fs::path dir_;
    std::unique_ptr<Farm> farm_;
};

TEST_F(SceneAccessTest, ForgedSceneNamingAServerFileIsRefusedWithoutLeakingIt) {
    const fs::path& dir = dir_;
    // A file of the server's own disk, in its data directory and outside.
    std::ofstream(dir / "data" / "secret.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    const std::string targets[] = {"/etc/hostname", (dir / "data" / "secret.obj").string(),
                                   "../secret.obj", "secret.obj", "/no/such/file.obj"};
    for (const std::string& target : targets) {
        const std::string json = ForgedScene(target);
        const absl::StatusOr<std::string> job = SubmitScene(*farm_, json);
        ASSERT_FALSE(job.ok()) << target;
        EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_EQ(job.status().message(), "scene.json: shapes[0].file \"" + target +
                                              "\": not among the files uploaded with the scene");
    }
}

// Submission loads the scene with its media: a grid whose .vdb was not uploaded is refused
// naming the field, and a method that does not render the media is refused naming both.
TEST_F(SceneAccessTest, MediaAreCheckedAtSubmission) {
    // ForgedScene's lamp, its mesh a sphere inside `media`'s "fog".
    const auto with = [](const std::string& media) {
        std::string json = ForgedScene("");
        const std::string mesh = R"({"type": "mesh", "material": "lamp", "file": ""})";
        json.replace(json.find(mesh), mesh.size(),
                     R"({"type": "sphere", "material": "lamp", "center": [0, 0, 1], )"
                     R"("radius": 0.5, "exterior": "fog"})");
        return json.insert(json.rfind('}'), R"(, "media": {)" + media + "}");
    };

    const absl::StatusOr<std::string> missing = SubmitScene(
        *farm_, with(R"("fog": {"type": "grid", "file": "fog.vdb", "sigma_s": [1, 1, 1]})"),
        "path");
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(
        missing.status().message(),
        "scene.json: media.fog.file \"fog.vdb\": not among the files uploaded with the scene");

    const std::string fog = with(R"("fog": {"type": "homogeneous", "sigma_s": [1, 1, 1]})");
    const absl::StatusOr<std::string> light = SubmitScene(*farm_, fog, "light");
    ASSERT_FALSE(light.ok());
    EXPECT_EQ(light.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(light.status().message(),
              "method light: medium \"fog\" scatters light (sigma_s > 0): not yet supported by "
              "light; use --method path");
    const absl::StatusOr<std::string> path = SubmitScene(*farm_, fog, "path");
    EXPECT_TRUE(path.ok()) << path.status();
}

}  // namespace
}  // namespace lf
