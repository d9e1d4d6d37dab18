// A fixture for tests that load JSON scenes: a fresh folder the scene's files are written to,
// the scene parsed beside them, and the error a parse must give.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "lf/core/scene_loader.h"
#include "test_dir.h"

namespace lf::testing {

class SceneTest : public ::testing::Test {
  protected:
    void SetUp() override { dir_ = FreshTestDir("lf_scene"); }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    void Write(const std::string& name, const std::string& bytes) {
        std::ofstream(dir_ / name, std::ios::binary) << bytes;
    }

    absl::StatusOr<Scene> Parse(const std::string& json) {
        return ParseScene(json, "scene.json", ReadBeside(dir_.string()));
    }

    // Parsing must fail with a message containing `expected`.
    void ExpectError(const std::string& json, const std::string& expected,
                     absl::StatusCode code = absl::StatusCode::kInvalidArgument) {
        absl::StatusOr<Scene> scene = Parse(json);
        ASSERT_FALSE(scene.ok()) << "expected an error containing: " << expected;
        EXPECT_EQ(scene.status().code(), code) << scene.status();
        EXPECT_NE(scene.status().message().find(expected), std::string::npos)
            << "message: " << scene.status().message() << "\nexpected: " << expected;
    }

    std::filesystem::path dir_;
};

}  // namespace lf::testing
