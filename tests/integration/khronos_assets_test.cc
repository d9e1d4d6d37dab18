// Khronos' glTF sample assets (tests/scenes/khronos, listed in its manifest.txt): each loads,
// gives exactly the warnings the manifest lists (or fails with the error it names), and renders
// under a white sky without a NaN or infinite sample.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "lf/core/scene_loader.h"
#include "render_path.h"
#include "scene_log.h"

namespace lf {
namespace {

const std::string kDir = std::string(LF_TEST_SCENES) + "/khronos/";

struct Asset {
    std::string name;
    std::string camera = "auto";
    std::vector<std::string> warnings;
    std::string error;
};

// Failures name the asset, not its bytes.
void PrintTo(const Asset& asset, std::ostream* os) { *os << asset.name; }

// manifest.txt: "asset NAME" starts a block; "camera", "warn" and "error" lines fill it.
std::vector<Asset> ReadManifest() {
    std::ifstream in(kDir + "manifest.txt");
    EXPECT_TRUE(in) << kDir << "manifest.txt";
    std::vector<Asset> assets;
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
        if (line.empty() || line[0] == '#') continue;
        const size_t space = line.find(' ');
        const std::string key = line.substr(0, space);
        const std::string value = space == std::string::npos ? "" : line.substr(space + 1);
        if (key == "asset") {
            assets.push_back({.name = value});
        } else if (assets.empty() || value.empty()) {
            ADD_FAILURE() << "manifest.txt:" << number << ": expected \"asset NAME\" first";
        } else if (key == "camera") {
            assets.back().camera = value;
        } else if (key == "warn") {
            assets.back().warnings.push_back(value);
        } else if (key == "error") {
            assets.back().error = value;
        } else {
            ADD_FAILURE() << "manifest.txt:" << number << ": unknown key \"" << key << "\"";
        }
    }
    return assets;
}

// The scene log's lines for `path`, each without the "PATH: " every loader warning starts with.
std::vector<std::string> WarningsOf(const std::string& log, const std::string& path) {
    std::vector<std::string> warnings;
    std::istringstream lines(log);
    const std::string prefix = path + ": ";
    for (std::string line; std::getline(lines, line);) {
        warnings.push_back(line.starts_with(prefix) ? line.substr(prefix.size()) : line);
    }
    std::sort(warnings.begin(), warnings.end());
    return warnings;
}

std::string Lines(const std::vector<std::string>& lines) {
    std::string out;
    for (const std::string& line : lines) out += "\n  " + line;
    return out.empty() ? " (none)" : out;
}

class KhronosAsset : public ::testing::TestWithParam<Asset> {};

TEST_P(KhronosAsset, LoadsWithItsWarningsAndRendersFinite) {
    const Asset& asset = GetParam();
    const std::string path = kDir + asset.name + "/" + asset.name + ".gltf";
    std::ostringstream& log = testing::CapturedSceneLog();
    spdlog::get("scene")->set_pattern("%v");
    log.str("");
    absl::StatusOr<Scene> scene =
        LoadScene(path, {.camera = asset.camera, .width = 48, .height = 48});
    if (!asset.error.empty()) {
        ASSERT_FALSE(scene.ok()) << path << " loads, but the manifest expects: " << asset.error;
        EXPECT_NE(scene.status().message().find(asset.error), std::string::npos) << scene.status();
        return;
    }
    ASSERT_TRUE(scene.ok()) << scene.status();

    std::vector<std::string> expected = asset.warnings;
    std::sort(expected.begin(), expected.end());
    const std::vector<std::string> given = WarningsOf(log.str(), path);
    std::vector<std::string> unexpected, missing;
    std::set_difference(given.begin(), given.end(), expected.begin(), expected.end(),
                        std::back_inserter(unexpected));
    std::set_difference(expected.begin(), expected.end(), given.begin(), given.end(),
                        std::back_inserter(missing));
    EXPECT_TRUE(unexpected.empty() && missing.empty())
        << asset.name << ": warnings not in manifest.txt:" << Lines(unexpected)
        << "\nwarnings in manifest.txt not given:" << Lines(missing);

    // A white sky lights every material, also of assets that bring no light.
    if (!scene->environment) scene->environment = EnvironmentLight{};
    const testing::PathRender render = testing::RenderPath(*scene, 4);
    EXPECT_EQ(render.out.stats.invalid_samples, 0u);
    double sum = 0;
    for (const char* channel : {"R", "G", "B"}) {
        for (const float v : *render.out.image.FindChannel(channel)) {
            ASSERT_TRUE(std::isfinite(v)) << channel;
            sum += v;
        }
    }
    // The camera sees the asset or the sky: never a black frame.
    EXPECT_GT(sum, 0);
}

INSTANTIATE_TEST_SUITE_P(Manifest, KhronosAsset, ::testing::ValuesIn(ReadManifest()),
                         [](const ::testing::TestParamInfo<Asset>& info) {
                             return info.param.name;
                         });

}  // namespace
}  // namespace lf
