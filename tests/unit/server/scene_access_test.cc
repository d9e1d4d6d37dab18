// A submission reaches only the files uploaded with it: a forged scene naming a file of the
// server's own disk is refused with a message naming the scene's field and nothing of the
// server (its data directory, whether the file exists, or what it holds).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "lf/job/digest.h"
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
        JobSpec spec;
        spec.scene = {"scene.json", Sha256Hex(json), json.size()};
        auto upload = (*farm)->StartUpload(spec.scene.hash, json.size());
        ASSERT_TRUE(upload.ok()) << upload.status();
        ASSERT_TRUE((*upload)->Append(json).ok());
        ASSERT_TRUE((*upload)->Finish().ok());

        const absl::StatusOr<std::string> job = (*farm)->Submit(spec);
        ASSERT_FALSE(job.ok()) << target;
        EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_EQ(job.status().message(), "scene.json: shapes[0].file \"" + target +
                                              "\": not among the files uploaded with the scene");
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
