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

TEST(SceneAccessTest, ForgedSceneNamingAServerFileIsRefusedWithoutLeakingIt) {
    const fs::path dir = fs::temp_directory_path() / ("lf_access_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    FarmOptions options;
    options.data_dir = (dir / "data").string();
    absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
    ASSERT_TRUE(farm.ok()) << farm.status();
    // A file of the server's own disk, in its data directory and outside.
    std::ofstream(dir / "data" / "secret.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    const std::string targets[] = {"/etc/hostname", (dir / "data" / "secret.obj").string(),
                                   "../secret.obj", "secret.obj", "/no/such/file.obj"};
    for (const std::string& target : targets) {
        const std::string json = ForgedScene(target);
        const absl::StatusOr<std::string> job = SubmitScene(**farm, json);
        ASSERT_FALSE(job.ok()) << target;
        EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_EQ(job.status().message(), "scene.json: shapes[0].file \"" + target +
                                              "\": not among the files uploaded with the scene");
    }
    fs::remove_all(dir);
}

// Submission loads the scene with its media: a grid whose .vdb was not uploaded is refused
// naming the field, and a method that does not render the media is refused naming both.
TEST(SceneAccessTest, MediaAreCheckedAtSubmission) {
    const fs::path dir = fs::temp_directory_path() / ("lf_media_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    FarmOptions options;
    options.data_dir = (dir / "data").string();
    absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
    ASSERT_TRUE(farm.ok()) << farm.status();
    const std::string scene =
        R"({"camera": {"position": [0, 0, -1], "look_at": [0, 0, 0], "fov_y_deg": 40,
                       "resolution": [4, 4]},
            "materials": {"lamp": {"type": "lambert", "reflectance": [0.5, 0.5, 0.5],
                                   "emission": [1, 1, 1]}},
            "media": {MEDIA},
            "shapes": [{"type": "quad", "material": "lamp", "exterior": "fog",
                        "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]}]})";
    const auto with = [&](const std::string& media) {
        std::string json = scene;
        return json.replace(json.find("MEDIA"), 5, media);
    };

    const absl::StatusOr<std::string> missing = SubmitScene(
        **farm, with(R"("fog": {"type": "grid", "file": "fog.vdb", "sigma_s": [1, 1, 1]})"),
        "path");
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(
        missing.status().message(),
        "scene.json: media.fog.file \"fog.vdb\": not among the files uploaded with the scene");

    const std::string fog = with(R"("fog": {"type": "homogeneous", "sigma_s": [1, 1, 1]})");
    const absl::StatusOr<std::string> bdpt = SubmitScene(**farm, fog, "bdpt");
    ASSERT_FALSE(bdpt.ok());
    EXPECT_EQ(bdpt.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_EQ(bdpt.status().message(),
              "method bdpt: medium \"fog\" scatters light (sigma_s > 0): not yet supported by "
              "bdpt; use --method path");
    const absl::StatusOr<std::string> path = SubmitScene(**farm, fog, "path");
    EXPECT_TRUE(path.ok()) << path.status();
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
