// The scene size limit: a blob or a job above it is refused before anything is stored or
// planned, with the flag that raises it named.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "lf/server/farm.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

TEST(FarmLimitsTest, SceneAboveTheSizeLimitIsRefusedBeforeItIsStoredOrPlanned) {
    const fs::path dir = fs::temp_directory_path() / ("lf_limits_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    FarmOptions options;
    options.data_dir = dir.string();
    options.limits.max_scene_bytes = 1000;
    absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
    ASSERT_TRUE(farm.ok()) << farm.status();

    const std::string hash(64, 'a');
    const auto upload = (*farm)->StartUpload(hash, 1001);
    EXPECT_EQ(upload.status().code(), absl::StatusCode::kResourceExhausted);
    EXPECT_NE(upload.status().message().find("--max-scene-mb"), std::string_view::npos);

    JobSpec spec;
    spec.scene = {"scene.json", hash, 600};
    spec.files = {{"mesh.obj", std::string(64, 'b'), 401}};
    const absl::StatusOr<std::string> job = (*farm)->Submit(spec);
    EXPECT_EQ(job.status().code(), absl::StatusCode::kResourceExhausted);
    EXPECT_NE(job.status().message().find("1001 bytes"), std::string_view::npos) << job.status();
    EXPECT_TRUE((*farm)->scheduler().List()->empty());
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
